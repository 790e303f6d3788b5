// A C++ user of cosleec_interfaces on ROS 2, built by tests/ros/test_cpp.py with g++ against
// the headers and libraries scripts/build-interfaces installs into .venv-ros2 (the ros-jazzy-*
// wheels have rcl but not rclcpp, so the client below is written over rcl, as rclcpp is).
//
//   cosleec_ros2 print
//       fills a Decision and a permission request and response, prints each with the
//       generated to_yaml (after a line "=== <type name>"), and the Decision serialized by
//       the C++ type support (rmw_serialize) as "=== cdr" and one line of hex.
//   cosleec_ros2 ask SERVICE EVENT SOURCE TIMEOUT_S
//       calls the Manager node's permission service SERVICE (cosleec_interfaces/srv/
//       AskPermission) with the C++ types, asking again every 2 s until it answers or
//       TIMEOUT_S passes; prints the response with to_yaml. Exit 1 without an answer.
// Exit 2 on bad arguments.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <thread>

#include "cosleec_interfaces/msg/decision.hpp"
#include "cosleec_interfaces/srv/ask_permission.hpp"
#include "rcl/graph.h"
#include "rcl/error_handling.h"
#include "rcl/rcl.h"
#include "rmw/serialized_message.h"
#include "rmw/rmw.h"
#include "rosidl_typesupport_cpp/message_type_support.hpp"
#include "rosidl_typesupport_cpp/service_type_support.hpp"

namespace msg = cosleec_interfaces::msg;
namespace srv = cosleec_interfaces::srv;
using Clock = std::chrono::steady_clock;

static msg::Decision a_decision()
{
  msg::Decision d;
  d.header.stamp.sec = 12;
  d.header.frame_id = "map";
  d.id = 7;
  d.session = "s-1";
  d.trigger = "CurtainOpenRequest";
  d.rule = "R1";
  d.clause = 1;
  d.layer = "R1.1";
  d.semantics = "last-wins";
  msg::MeasureValue v;
  v.name = "userUndressed";
  v.kind = msg::MeasureValue::BOOLEAN;
  v.boolean = true;
  d.values.push_back(v);
  msg::Obligation o;
  o.decision = 7;
  o.rule = "R1";
  o.event = "CurtainOpened";
  o.prohibition = true;
  o.deadline = 60.0;
  d.obligations.push_back(o);
  d.missing.push_back("roomDark");
  d.explanation = "R1: do not open the curtains, because userUndressed was true";
  d.sender = "cpp";
  d.seq = 3;
  return d;
}

static int print_types()
{
  const msg::Decision d = a_decision();
  srv::AskPermission::Request req;
  req.event = "OpenCurtains";
  req.source = "cpp_planner";
  srv::AskPermission::Response resp;
  resp.permitted = false;
  resp.rules = {"R1"};
  resp.reason = "OpenCurtains is forbidden by R1";
  std::cout << "=== " << rosidl_generator_traits::name<msg::Decision>() << "\n" << msg::to_yaml(d)
            << "=== " << rosidl_generator_traits::name<srv::AskPermission::Request>() << "\n"
            << srv::to_yaml(req) << "=== "
            << rosidl_generator_traits::name<srv::AskPermission::Response>() << "\n"
            << srv::to_yaml(resp) << "=== " << rosidl_generator_traits::name<srv::AskPermission>()
            << "\n";

  rmw_serialized_message_t cdr = rmw_get_zero_initialized_serialized_message();
  rcutils_allocator_t alloc = rcutils_get_default_allocator();
  if (rmw_serialized_message_init(&cdr, 0, &alloc) != RMW_RET_OK ||
      rmw_serialize(&d, rosidl_typesupport_cpp::get_message_type_support_handle<msg::Decision>(),
                    &cdr) != RMW_RET_OK) {
    std::cerr << "rmw_serialize failed: " << rcutils_get_error_string().str << "\n";
    return 1;
  }
  std::cout << "=== cdr\n";
  for (size_t i = 0; i < cdr.buffer_length; ++i) std::printf("%02x", cdr.buffer[i]);
  std::cout << "\n";
  return rmw_serialized_message_fini(&cdr) == RMW_RET_OK ? 0 : 1;
}

#define CHECK(call)                                                               \
  do {                                                                            \
    if ((call) != RCL_RET_OK) {                                                   \
      std::cerr << #call << " failed: " << rcl_get_error_string().str << "\n"; \
      std::exit(1);                                                               \
    }                                                                             \
  } while (0)

// Wait up to `left` for the response to request `seq`; true once it is in `resp`.
static bool take_answer(rcl_context_t * ctx, rcl_client_t * client, int64_t seq,
                        Clock::duration left, srv::AskPermission::Response * resp)
{
  rcl_wait_set_t ws = rcl_get_zero_initialized_wait_set();
  CHECK(rcl_wait_set_init(&ws, 0, 0, 0, 1, 0, 0, ctx, rcl_get_default_allocator()));
  const auto end = Clock::now() + left;
  bool got = false;
  while (!got && Clock::now() < end) {
    CHECK(rcl_wait_set_clear(&ws));
    CHECK(rcl_wait_set_add_client(&ws, client, nullptr));
    const rcl_ret_t rc = rcl_wait(&ws, RCL_MS_TO_NS(200));
    if (rc == RCL_RET_TIMEOUT || ws.clients[0] == nullptr) continue;
    CHECK(rc);
    rmw_request_id_t header;
    const rcl_ret_t taken = rcl_take_response(client, &header, resp);
    if (taken == RCL_RET_CLIENT_TAKE_FAILED) continue;
    CHECK(taken);
    got = header.sequence_number == seq;  // an answer to an earlier try is not this one's
  }
  CHECK(rcl_wait_set_fini(&ws));
  return got;
}

static int ask(const char * service, const char * event, const char * source, double timeout_s)
{
  rcl_init_options_t options = rcl_get_zero_initialized_init_options();
  CHECK(rcl_init_options_init(&options, rcl_get_default_allocator()));
  rcl_context_t ctx = rcl_get_zero_initialized_context();
  CHECK(rcl_init(0, nullptr, &options, &ctx));
  rcl_node_t node = rcl_get_zero_initialized_node();
  rcl_node_options_t node_options = rcl_node_get_default_options();
  CHECK(rcl_node_init(&node, "cosleec_cpp_client", "", &ctx, &node_options));
  rcl_client_t client = rcl_get_zero_initialized_client();
  rcl_client_options_t client_options = rcl_client_get_default_options();
  CHECK(rcl_client_init(&client, &node,
                        rosidl_typesupport_cpp::get_service_type_support_handle<srv::AskPermission>(),
                        service, &client_options));

  srv::AskPermission::Request req;
  req.event = event;
  req.source = source;
  srv::AskPermission::Response resp;
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(timeout_s));
  bool answered = false;
  while (!answered && Clock::now() < end) {
    bool up = false;
    CHECK(rcl_service_server_is_available(&node, &client, &up));
    if (!up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      continue;
    }
    int64_t seq = 0;
    CHECK(rcl_send_request(&client, &req, &seq));
    answered = take_answer(&ctx, &client, seq, std::min<Clock::duration>(std::chrono::seconds(2),
                                                                         end - Clock::now()), &resp);
  }
  if (answered) std::cout << srv::to_yaml(resp);
  else std::cerr << "no answer from " << service << " within " << timeout_s << " s\n";

  CHECK(rcl_client_fini(&client, &node));
  CHECK(rcl_node_fini(&node));
  CHECK(rcl_shutdown(&ctx));
  CHECK(rcl_context_fini(&ctx));
  CHECK(rcl_init_options_fini(&options));
  return answered ? 0 : 1;
}

int main(int argc, char ** argv)
{
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "print" && argc == 2) return print_types();
  if (mode == "ask" && argc == 6) return ask(argv[2], argv[3], argv[4], std::atof(argv[5]));
  std::cerr << "usage: cosleec_ros2 print | cosleec_ros2 ask SERVICE EVENT SOURCE TIMEOUT_S\n";
  return 2;
}
