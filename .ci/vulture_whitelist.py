"""Names vulture cannot see used: public API used from outside, and callbacks called by name.

Reviewed by hand: each entry says why it is not dead. CI runs
`vulture src/cosleec .ci/vulture_whitelist.py --min-confidence 60`; a new finding is either dead
code (delete it) or belongs here with its reason.
"""
# ruff: noqa
# type: ignore

snapshot_id  # unused variable (src/cosleec/cop/dispatch.py:74)  -- a field of DispatchRecord, read by dispatch hooks (tracing, audit)
_.builds  # unused attribute (src/cosleec/cop/dispatch.py:176)  -- how many chains a layered function built: introspection of the chain cache
_.builds  # unused attribute (src/cosleec/cop/dispatch.py:314)  -- how many chains a layered function built: introspection of the chain cache
_.fire  # unused method (src/cosleec/cop/events.py:50)  -- Transitions.fire: public COP API (event-triggered switching)
_.__wrapped__  # unused attribute (src/cosleec/cop/extent.py:191)  -- the functools convention for wrappers (inspect.unwrap)
_.on_enter  # unused method (src/cosleec/cop/layer.py:54)  -- Layer.on_enter/on_exit: public COP API (enter/exit hooks)
_.on_exit  # unused method (src/cosleec/cop/layer.py:63)  -- Layer.on_enter/on_exit: public COP API (enter/exit hooks)
_.refuse_and_explain  # unused method (src/cosleec/demo/assistive_care/tasks.py:74)  -- demo task methods found by their @hedge marks
_.warn_then_open  # unused method (src/cosleec/demo/assistive_care/tasks.py:81)  -- demo task methods found by their @hedge marks
FALSE  # unused variable (src/cosleec/lang/hedges.py:45)  -- Unknowns.FALSE: chosen by value ("false") from options
always_accept  # unused variable (src/cosleec/lang/lexer.py:201)  -- attributes and methods Lark calls on a lexer/postlexer
_.process  # unused method (src/cosleec/lang/lexer.py:206)  -- attributes and methods Lark calls on a lexer/postlexer
_.wait_idle  # unused method (src/cosleec/nodes/transport.py:135)  -- LocalBus.wait_idle: for harnesses driving the in-process bus
_.publish_typed  # unused method (src/cosleec/ros/ros1.py:79)  -- typed publishing for simulators and system tests
_.typed_subscribers  # unused method (src/cosleec/ros/ros1.py:87)  -- typed publishing for simulators and system tests
_.publish_typed  # unused method (src/cosleec/ros/ros2.py:135)  -- typed publishing for simulators and system tests
_.typed_subscribers  # unused method (src/cosleec/ros/ros2.py:145)  -- typed publishing for simulators and system tests
proceed  # unused variable (src/cosleec/runtime/implementations.py:147)  -- a clause variant receives proceed= from COP and deliberately does not call it
_.active  # unused property (src/cosleec/runtime/obligations.py:117)  -- Tracker.active: the obligations in force, for callers and tests
_.event  # Task.event: the public way a task reports an event
_.layers_message  # Driver.layers_message: the last `layers` message, for harnesses waiting on a switch

# The transformers' methods are the grammar's rule callbacks: Lark calls them by rule name.
_.prule  # unused method (src/cosleec/lang/paper.py:26)
_.pclause  # unused method (src/cosleec/lang/paper.py:33)
_.pitems  # unused method (src/cosleec/lang/paper.py:36)
_.pitem  # unused method (src/cosleec/lang/paper.py:39)
_.list_first  # unused method (src/cosleec/lang/transformer.py:66)
_.list_more  # unused method (src/cosleec/lang/transformer.py:69)
_.def_block  # unused method (src/cosleec/lang/transformer.py:78)
_.rule_block  # unused method (src/cosleec/lang/transformer.py:81)
_.concern_block  # unused method (src/cosleec/lang/transformer.py:84)
_.purpose_block  # unused method (src/cosleec/lang/transformer.py:87)
_.relation_block  # unused method (src/cosleec/lang/transformer.py:90)
_.event_decl  # unused method (src/cosleec/lang/transformer.py:94)
_.measure_decl  # unused method (src/cosleec/lang/transformer.py:97)
_.boolean_type  # unused method (src/cosleec/lang/transformer.py:100)
_.numeric_type  # unused method (src/cosleec/lang/transformer.py:103)
_.scale_type  # unused method (src/cosleec/lang/transformer.py:106)
_.constant_decl  # unused method (src/cosleec/lang/transformer.py:109)
_.const_int  # unused method (src/cosleec/lang/transformer.py:113)
_.const_neg  # unused method (src/cosleec/lang/transformer.py:116)
_.const_name  # unused method (src/cosleec/lang/transformer.py:119)
_.const_arrow  # unused method (src/cosleec/lang/transformer.py:122)
_.fluent_decl  # unused method (src/cosleec/lang/transformer.py:125)
_.name_list  # unused method (src/cosleec/lang/transformer.py:128)
_.response_body  # unused method (src/cosleec/lang/transformer.py:138)
_.inner_body  # unused method (src/cosleec/lang/transformer.py:142)
_.defeater  # unused method (src/cosleec/lang/transformer.py:165)
_.within_interval  # unused method (src/cosleec/lang/transformer.py:171)
_.time_unit  # unused method (src/cosleec/lang/transformer.py:178)
_.and_  # unused method (src/cosleec/lang/transformer.py:182)
_.or_  # unused method (src/cosleec/lang/transformer.py:185)
_.not_  # unused method (src/cosleec/lang/transformer.py:188)
_.compare  # unused method (src/cosleec/lang/transformer.py:191)
_.rel_op  # unused method (src/cosleec/lang/transformer.py:195)
_.mul  # unused method (src/cosleec/lang/transformer.py:204)
_.bool_lit  # unused method (src/cosleec/lang/transformer.py:207)
_.int_lit  # unused method (src/cosleec/lang/transformer.py:210)
_.neg_int  # unused method (src/cosleec/lang/transformer.py:213)
_.decimal_lit  # unused method (src/cosleec/lang/transformer.py:218)
_.arrow_name  # unused method (src/cosleec/lang/transformer.py:224)
_.braced_name  # unused method (src/cosleec/lang/transformer.py:227)
_.paren  # unused method (src/cosleec/lang/transformer.py:230)
_.situation  # unused method (src/cosleec/lang/transformer.py:245)
_.exists_body  # unused method (src/cosleec/lang/transformer.py:249)
_.when_body  # unused method (src/cosleec/lang/transformer.py:252)
_.ext_response  # unused method (src/cosleec/lang/transformer.py:259)
_.event_relation  # unused method (src/cosleec/lang/transformer.py:263)
_.measure_relation  # unused method (src/cosleec/lang/transformer.py:266)
_.measure_invariant  # unused method (src/cosleec/lang/transformer.py:269)
_.event_measure_relation  # unused method (src/cosleec/lang/transformer.py:272)
_.until_relation  # unused method (src/cosleec/lang/transformer.py:275)
_.for_relation  # unused method (src/cosleec/lang/transformer.py:278)
measure_rel  # unused variable (src/cosleec/lang/transformer.py:284)
event_measure_rel  # unused variable (src/cosleec/lang/transformer.py:285)
