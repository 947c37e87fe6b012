#include "pc_ekf/ros/master_watch.h"

#include <ros/connection_manager.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <ros/service_manager.h>
#include <ros/xmlrpc_manager.h>
#include <xmlrpcpp/XmlRpc.h>

#include <chrono>
#include <cstdio>
#include <set>
#include <utility>

namespace pc_ekf {
namespace {

using XmlRpc::XmlRpcValue;

// Master API call; false when the master does not answer or refuses.
bool callMaster(const std::string& method, XmlRpcValue args, XmlRpcValue& payload) {
  XmlRpcValue result;
  return ros::master::execute(method, args, result, payload, false);
}

XmlRpcValue callerArgs() {
  XmlRpcValue args;
  args[0] = ros::this_node::getName();
  return args;
}

// This process's own Slave API (getBusInfo, publisherUpdate): what roscpp
// holds but does not expose in C++. Served by roscpp's XML-RPC thread.
bool callSelf(const std::string& method, const XmlRpcValue& args, XmlRpcValue& payload) {
  std::string host;
  std::uint32_t port = 0;
  if (!ros::network::splitURI(ros::XMLRPCManager::instance()->getServerURI(), host, port)) {
    return false;
  }
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpcValue result;
  if (!client.execute(method.c_str(), args, result) || result.getType() != XmlRpcValue::TypeArray ||
      result.size() < 3 || static_cast<int>(result[0]) != 1) {
    return false;
  }
  payload = result[2];
  return true;
}

std::string wallTimeText() {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", ros::WallTime::now().toSec());
  return text;
}

}  // namespace

MasterWatch::MasterWatch(std::vector<std::string> services, double period)
    : services_(std::move(services)), period_(period), thread_([this] { loop(); }) {}

MasterWatch::~MasterWatch() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

MasterStatus MasterWatch::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

void MasterWatch::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    lock.unlock();
    check();
    lock.lock();
    wake_.wait_for(lock, std::chrono::duration<double>(period_), [this] { return stop_; });
  }
}

void MasterWatch::check() {
  XmlRpcValue pid;
  const bool reachable = callMaster("getPid", callerArgs(), pid) &&
                         pid.getType() == XmlRpcValue::TypeInt;
  int previous_pid = 0;
  bool was_reachable = true;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    previous_pid = status_.pid;
    was_reachable = status_.reachable;
    status_.reachable = reachable;
    if (reachable) status_.pid = static_cast<int>(pid);
  }
  if (!reachable) {
    if (was_reachable) {
      ROS_WARN("%s: the ROS master at %s does not answer; estimating goes on, checking every %.1f s",
               ros::this_node::getName().c_str(), ros::master::getURI().c_str(), period_);
    }
    return;
  }
  if (previous_pid == static_cast<int>(pid) && was_reachable) return;  // the same master
  // Another master, or the same one back: does it know this node?
  XmlRpcValue args = callerArgs(), uri;
  args[1] = ros::this_node::getName();
  if (callMaster("lookupNode", args, uri)) return;
  const std::string report = reregister();
  ROS_WARN("%s: new ROS master at %s (pid %d): %s", ros::this_node::getName().c_str(),
           ros::master::getURI().c_str(), static_cast<int>(pid), report.c_str());
  std::lock_guard<std::mutex> lock(mutex_);
  ++status_.restarts;
  status_.last_change = wallTimeText();
  status_.last_report = report;
}

std::string MasterWatch::reregister() {
  const std::string me = ros::this_node::getName();
  const std::string api = ros::XMLRPCManager::instance()->getServerURI();
  XmlRpcValue bus, publications, subscriptions;
  if (!callSelf("getBusInfo", callerArgs(), bus) ||
      !callSelf("getPublications", callerArgs(), publications) ||
      !callSelf("getSubscriptions", callerArgs(), subscriptions)) {
    return "re-registration failed: this node's own XML-RPC API did not answer";
  }
  int topics = 0, failed = 0, services = 0;
  for (int i = 0; i < publications.size(); ++i) {
    XmlRpcValue args = callerArgs(), subscribers;
    args[1] = publications[i][0];
    args[2] = publications[i][1];
    args[3] = api;
    callMaster("registerPublisher", args, subscribers) ? ++topics : ++failed;
  }
  for (int i = 0; i < subscriptions.size(); ++i) {
    const std::string topic = static_cast<std::string&>(subscriptions[i][0]);
    XmlRpcValue args = callerArgs(), publishers;
    args[1] = topic;
    args[2] = subscriptions[i][1];
    args[3] = api;
    if (!callMaster("registerSubscriber", args, publishers)) {
      ++failed;
      continue;
    }
    ++topics;
    // roscpp drops links to publishers missing from an update: the ones
    // still connected (they may not have re-registered) stay in it.
    std::set<std::string> uris;
    for (int j = 0; j < bus.size(); ++j) {
      if (static_cast<std::string&>(bus[j][2]) == "i" &&
          static_cast<std::string&>(bus[j][4]) == topic) uris.insert(static_cast<std::string&>(bus[j][1]));
    }
    for (int j = 0; j < publishers.size(); ++j) {
      uris.insert(static_cast<std::string&>(publishers[j]));
    }
    XmlRpcValue update, ignored;
    update[0] = std::string("/master");
    update[1] = topic;
    update[2].setSize(0);
    for (const std::string& u : uris) update[2][update[2].size()] = u;
    callSelf("publisherUpdate", update, ignored);
  }
  const std::string service_api = "rosrpc://" + ros::network::getHost() + ":" +
                                  std::to_string(ros::ConnectionManager::instance()->getTCPPort());
  for (const std::string& name : services_) {
    if (!ros::ServiceManager::instance()->lookupServicePublication(name)) continue;
    XmlRpcValue args = callerArgs(), ignored;
    args[1] = name;
    args[2] = service_api;
    args[3] = api;
    callMaster("registerService", args, ignored) ? ++services : ++failed;
  }
  return "registered " + std::to_string(topics) + " topics and " + std::to_string(services) +
         " services again" + (failed ? " (" + std::to_string(failed) + " refused)" : "");
}

}  // namespace pc_ekf
