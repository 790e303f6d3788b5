// A C++ user of cosleec_interfaces on ROS 1, built by tests/ros/test_cpp.py with g++ against
// Debian's roscpp headers and the gencpp headers scripts/build-interfaces writes into
// build/ros1_interfaces/include.
//
//   cosleec_ros1 print
//       fills a Decision and a permission request and response and prints each with the
//       generated operator<< (after a line "=== <type name> <md5sum>"), then the service type
//       ("=== <type name> <md5sum>" alone) and the Decision serialized by roscpp as
//       "=== wire" and one line of hex.
//   cosleec_ros1 ask SERVICE EVENT SOURCE TIMEOUT_S
//       calls the Manager node's permission service SERVICE (cosleec_interfaces/AskPermission)
//       with roscpp (ROS_MASTER_URI from the environment), once it is up within TIMEOUT_S;
//       prints the response with operator<<. Exit 1 without an answer.
// Exit 2 on bad arguments.

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <ros/serialization.h>

#include "cosleec_interfaces/AskPermission.h"
#include "cosleec_interfaces/Decision.h"

namespace ci = cosleec_interfaces;

template <class T>
static void print(const T & m)
{
  std::cout << "=== " << ros::message_traits::datatype<T>() << " " << ros::message_traits::md5sum<T>()
            << "\n" << m;
}

static ci::Decision a_decision()
{
  ci::Decision d;
  d.header.stamp = ros::Time(12, 0);
  d.header.frame_id = "map";
  d.id = 7;
  d.session = "s-1";
  d.trigger = "CurtainOpenRequest";
  d.rule = "R1";
  d.clause = 1;
  d.layer = "R1.1";
  d.semantics = "last-wins";
  ci::MeasureValue v;
  v.name = "userUndressed";
  v.kind = ci::MeasureValue::BOOLEAN;
  v.boolean = true;
  d.values.push_back(v);
  ci::Obligation o;
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
  const ci::Decision d = a_decision();
  ci::AskPermission::Request req;
  req.event = "OpenCurtains";
  req.source = "cpp_planner";
  ci::AskPermission::Response resp;
  resp.permitted = false;
  resp.rules.push_back("R1");
  resp.reason = "OpenCurtains is forbidden by R1";
  print(d);
  print(req);
  print(resp);
  std::cout << "=== " << ros::service_traits::datatype<ci::AskPermission>() << " "
            << ros::service_traits::md5sum<ci::AskPermission>() << "\n";

  std::vector<uint8_t> wire(ros::serialization::serializationLength(d));
  ros::serialization::OStream out(wire.data(), wire.size());
  ros::serialization::serialize(out, d);
  std::cout << "=== wire\n";
  for (uint8_t b : wire) std::printf("%02x", b);
  std::cout << "\n";
  return 0;
}

static int ask(int argc, char ** argv)
{
  const std::string service = argv[2];
  ros::init(argc, argv, "cosleec_cpp_client",
            ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
  ci::AskPermission call;
  call.request.event = argv[3];
  call.request.source = argv[4];
  const double timeout_s = std::atof(argv[5]);
  if (!ros::service::waitForService(service, ros::Duration(timeout_s)) ||
      !ros::service::call(service, call)) {
    std::cerr << "no answer from " << service << " within " << timeout_s << " s\n";
    return 1;
  }
  std::cout << call.response;
  return 0;
}

int main(int argc, char ** argv)
{
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "print" && argc == 2) return print_types();
  if (mode == "ask" && argc == 6) return ask(argc, argv);
  std::cerr << "usage: cosleec_ros1 print | cosleec_ros1 ask SERVICE EVENT SOURCE TIMEOUT_S\n";
  return 2;
}
