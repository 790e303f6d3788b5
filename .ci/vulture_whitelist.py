"""Names vulture cannot see used: public API used from outside, and callbacks called by name.

Reviewed by hand: each entry says why it is not dead. CI runs
`vulture src/cosleec .ci/vulture_whitelist.py --min-confidence 60`; a new finding is either dead
code (delete it) or belongs here with its reason.
"""
# ruff: noqa
# type: ignore

snapshot_id  # a field of DispatchRecord, read by dispatch hooks (tracing, audit)
_.builds  # how many chains a layered function built: introspection of the chain cache
_.fire  # Transitions.fire: public COP API (event-triggered switching)
_.__wrapped__  # the functools convention for wrappers (inspect.unwrap)
_.on_enter  # Layer.on_enter/on_exit: public COP API (enter/exit hooks)
_.on_exit  # Layer.on_enter/on_exit: public COP API (enter/exit hooks)
_.refuse_and_explain  # demo task methods found by their @hedge marks
_.warn_then_open  # demo task methods found by their @hedge marks
FALSE  # Unknowns.FALSE: chosen by value ("false") from options
always_accept  # attributes and methods Lark calls on a lexer/postlexer
_.process  # attributes and methods Lark calls on a lexer/postlexer
_.wait_idle  # LocalBus.wait_idle: for harnesses driving the in-process bus
_.publish_typed  # typed publishing for simulators and system tests
_.typed_subscribers  # typed publishing for simulators and system tests
proceed  # a clause variant receives proceed= from COP and deliberately does not call it
_.active  # Tracker.active: the obligations in force, for callers and tests
_.layers_message  # Driver.layers_message: the last `layers` message, for harnesses waiting on a switch
_.updated  # Express.updated: the updates the express lane took, read by its tests

# The transformers' methods are the grammar's rule callbacks: Lark calls them by rule name.
_.prule  #
_.pclause  #
_.pitems  #
_.pitem  #
_.list_first  #
_.list_more  #
_.def_block  #
_.rule_block  #
_.concern_block  #
_.purpose_block  #
_.relation_block  #
_.event_decl  #
_.measure_decl  #
_.boolean_type  #
_.numeric_type  #
_.scale_type  #
_.constant_decl  #
_.const_int  #
_.const_signed  #
_.const_name  #
_.const_arrow  #
_.fluent_decl  #
_.name_list  #
_.response_body  #
_.inner_body  #
_.defeater  #
_.within_interval  #
_.time_unit  #
_.and_  #
_.or_  #
_.not_  #
_.compare  #
_.rel_op  #
_.mul  #
_.bool_lit  #
_.int_lit  #
_.signed_int  #
_.sign  #
_.decimal_lit  #
_.arrow_name  #
_.braced_name  #
_.paren  #
_.situation  #
_.exists_body  #
_.when_body  #
_.ext_response  #
_.event_relation  #
_.measure_relation  #
_.measure_invariant  #
_.event_measure_relation  #
_.until_relation  #
_.for_relation  #
_.priority_block  #
_.semantics_block  # a Lark transformer callback (the semantics_start block)
_.semantics_entry  #
_.chain_first  #
measure_rel  #
event_measure_rel  #
REFUSE  # UnknownEvents.REFUSE: chosen by value (unknown_events="refuse")
# fields of ROS messages, set for whoever reads them (cosleec_interfaces, diagnostic_msgs)
_.frame_id  #
_.window_start  #
_.previous  #
_.executor_alive  #
_.hardware_id  #
# rclpy's LifecycleNode calls these on each transition (ros.lifecycle.lifecycle_node)
_.on_configure  #
_.on_activate  #
_.on_deactivate  #
_.on_cleanup  #
_.on_shutdown  #
_.potherwise  # a Lark transformer callback of the paper notation (lang/paper.py)
_.should_exit  # uvicorn.Server.should_exit: uvicorn's main loop reads it (the web view stops its server so)
_.reuse  # IncrementalAnalyser.reuse: what the last check parsed again, for callers (tests, benchmarks/lsp_incremental)
pieces  # Reuse.pieces: how many pieces the text was cut into (with `reuse`)
# the language server's handlers: pygls calls them by the LSP method they are registered for
initialize  #
did_open  #
did_change  #
did_save  #
did_close  #
code_action  #
servers  # views/web_server.Server: uvicorn's Server reads it when it shuts down
__getattr__  # cosleec/__init__: the module's lazy exports (PEP 562), called by Python
__dir__  # cosleec/__init__: dir(cosleec) lists the lazy exports (PEP 562)
INTERNALS  # cosleec.runtime.INTERNALS: the face's internals, read by tests/unit/runtime/test_face.py
_.__doc__  # runtime/core.InForce sets its instance's __doc__: help() and documentation tools read it
_.task_failures  # runtime/stats.Stats counters are read by name (Stats.__getitem__, to_json)
task_failures  #
_.feedback_message  # py_trees Behaviour.feedback_message: what py_trees shows; cosleec.bt sets it
RosLink  # cosleec.ros.bt_client.RosLink: public API for behaviour trees on ROS 2 (docs/bt.md)
