#include "pc_ekf/ros/replay_options.h"

#include <xmlrpcpp/XmlRpcValue.h>

#include <cmath>
#include <sstream>

namespace pc_ekf {

namespace {

std::string describe(XmlRpc::XmlRpcValue value) {
  std::ostringstream o;
  value.write(o);
  return o.str();
}

[[noreturn]] void invalid(const ros::NodeHandle& nh, const std::string& name,
                          const std::string& value, const std::string& expected) {
  throw ReplayOptionError("parameter '" + nh.resolveName(name) + "': value " + value +
                          " invalid, expected " + expected);
}

// The parameter when set; a wrong type is an error, not a silent default.
void read(const ros::NodeHandle& nh, const std::string& name, bool* value) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(name, v)) return;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean) invalid(nh, name, describe(v), "true/false");
  *value = static_cast<bool>(v);
}

void read(const ros::NodeHandle& nh, const std::string& name, double* value, double min,
          const std::string& expected) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(name, v)) return;
  double d = 0.0;
  if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
    d = static_cast<double>(v);
  } else if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) {
    d = static_cast<int>(v);
  } else {
    invalid(nh, name, describe(v), expected);
  }
  if (!std::isfinite(d) || d < min) invalid(nh, name, describe(v), expected);
  *value = d;
}

void read(const ros::NodeHandle& nh, const std::string& name, int* value, int min,
          const std::string& expected) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(name, v)) return;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeInt || static_cast<int>(v) < min) {
    invalid(nh, name, describe(v), expected);
  }
  *value = static_cast<int>(v);
}

void read(const ros::NodeHandle& nh, const std::string& name, std::string* value) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(name, v)) return;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeString || static_cast<std::string>(v).empty()) {
    invalid(nh, name, describe(v), "a non-empty string");
  }
  *value = static_cast<std::string>(v);
}

// A list of topic names, or one string of names separated by spaces/commas
// (handy on the rosrun command line: _subscriber_topics:="a b").
void read(const ros::NodeHandle& nh, const std::string& name, std::vector<std::string>* value) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(name, v)) return;
  const std::string expected = "a list of topic names or one string of them";
  std::vector<std::string> out;
  if (v.getType() == XmlRpc::XmlRpcValue::TypeString) {
    std::string text = static_cast<std::string>(v);
    for (char& c : text) c = c == ',' ? ' ' : c;
    std::istringstream words(text);
    for (std::string w; words >> w;) out.push_back(w);
  } else if (v.getType() == XmlRpc::XmlRpcValue::TypeArray) {
    for (int i = 0; i < v.size(); ++i) {
      if (v[i].getType() != XmlRpc::XmlRpcValue::TypeString)
        invalid(nh, name, describe(v), expected);
      out.push_back(static_cast<std::string>(v[i]));
    }
  } else {
    invalid(nh, name, describe(v), expected);
  }
  *value = out;
}

}  // namespace

ReplayOptions loadReplayOptions(const ros::NodeHandle& nh) {
  ReplayOptions o;
  if (!nh.hasParam("bag")) {
    throw ReplayOptionError("parameter '" + nh.resolveName("bag") +
                            "' is required (the bag to replay, e.g. _bag:=FILE.bag)");
  }
  read(nh, "bag", &o.bag);
  read(nh, "rate", &o.rate, 0.0, "a finite rate >= 0 (1 = recorded timing, 0 = fastest)");
  read(nh, "wait_for_subscribers", &o.wait_for_subscribers);
  read(nh, "subscriber_topics", &o.subscriber_topics);
  read(nh, "min_subscribers", &o.min_subscribers, 0, "an integer >= 0");
  read(nh, "wait_timeout", &o.wait_timeout, 0.0, "seconds >= 0 (0 = forever)");
  read(nh, "start_delay", &o.start_delay, 0.0, "seconds >= 0");
  read(nh, "queue_size", &o.queue_size, 0, "an integer >= 0 (0 = the topic's message count)");
  read(nh, "loop", &o.loop);
  read(nh, "lossless", &o.lossless);
  read(nh, "lossless_topic", &o.lossless_topic);
  read(nh, "estimate_topic", &o.estimate_topic);
  read(nh, "lossless_timeout", &o.lossless_timeout, 1e-3, "seconds >= 0.001");
  read(nh, "publish_clock", &o.publish_clock);
  read(nh, "linger", &o.linger, 0.0, "seconds >= 0");
  return o;
}

}  // namespace pc_ekf
