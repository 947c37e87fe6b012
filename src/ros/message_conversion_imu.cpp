// sensor_msgs/Imu <-> IMU channels (message_conversion.h, issue 29).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

int indexOf(const std::vector<std::string>& names, const std::vector<std::string>& selected,
            const std::string& name) {
  if (std::find(selected.begin(), selected.end(), name) == selected.end()) return -1;
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

bool allZero(const boost::array<double, 9>& c) {
  return std::all_of(c.begin(), c.end(), [](double v) { return v == 0.0; });
}

struct Field {
  const char* name;  // "linear_acceleration" | "angular_velocity"
  const boost::array<double, 9>* covariance;
  // (axis 0..2, channel, value)
  std::vector<std::pair<int, std::pair<int, double>>> axes;
};

}  // namespace

const char* toString(ImuProblem p) {
  switch (p) {
    case ImuProblem::kNonFinite:
      return "non_finite";
    case ImuProblem::kNoData:
      return "no_data";
    case ImuProblem::kBadCovariance:
      return "bad_covariance";
  }
  return "?";
}

ImuChannels imuChannels(const std::vector<std::string>& channel_names,
                        const std::vector<std::string>& selected) {
  ImuChannels c;
  c.accel_x = indexOf(channel_names, selected, "accel_x");
  c.accel_y = indexOf(channel_names, selected, "accel_y");
  c.accel_z = indexOf(channel_names, selected, "accel_z");
  c.gyro_x = indexOf(channel_names, selected, "gyro_x");
  c.gyro_y = indexOf(channel_names, selected, "gyro_y");
  c.gyro_z = indexOf(channel_names, selected, "gyro_z");
  return c;
}

ImuConversion readingFromImu(const sensor_msgs::Imu& msg, const ImuChannels& ch) {
  ImuConversion out;
  out.reading.stamp_ns =
      static_cast<std::int64_t>(msg.header.stamp.sec) * 1000000000LL + msg.header.stamp.nsec;
  const auto& a = msg.linear_acceleration;
  const auto& w = msg.angular_velocity;
  Field fields[2] = {
      {"linear_acceleration", &msg.linear_acceleration_covariance,
       {{0, {ch.accel_x, a.x}}, {1, {ch.accel_y, a.y}}, {2, {ch.accel_z, a.z}}}},
      {"angular_velocity", &msg.angular_velocity_covariance,
       {{0, {ch.gyro_x, w.x}}, {1, {ch.gyro_y, w.y}}, {2, {ch.gyro_z, w.z}}}},
  };
  std::vector<std::pair<int, std::pair<double, double>>> taken;  // channel, (value, variance)
  static const char* axis_names[3] = {"x", "y", "z"};
  for (const Field& f : fields) {
    bool used = false;
    for (const auto& ax : f.axes) used = used || ax.second.first >= 0;
    if (!used) continue;
    const auto& cov = *f.covariance;
    if (cov[0] == -1.0) {
      out.problems.push_back(std::string(f.name) + "_covariance[0] = -1: no " + f.name +
                             " data (its channels not observed)");
      out.problem_kinds.push_back(ImuProblem::kNoData);
      continue;
    }
    const bool unknown = allZero(cov);
    if (unknown) ++out.unknown_covariances;
    for (const auto& ax : f.axes) {
      const int channel = ax.second.first;
      const double value = ax.second.second;
      if (channel < 0) continue;
      const std::string what = std::string(f.name) + "." + axis_names[ax.first];
      if (!std::isfinite(value)) {
        out.problems.push_back(what + " is " + std::to_string(value) + ": not observed");
        out.problem_kinds.push_back(ImuProblem::kNonFinite);
        continue;
      }
      double variance = kNaN;
      if (!unknown) {
        const double d = cov[static_cast<std::size_t>(4 * ax.first)];
        if (!std::isfinite(d) || d < 0.0) {
          out.problems.push_back(std::string(f.name) + "_covariance[" +
                                 std::to_string(4 * ax.first) + "] = " + std::to_string(d) +
                                 " is not a variance: measurement.sensor_std used");
          out.problem_kinds.push_back(ImuProblem::kBadCovariance);
        } else if (d > 0.0) {
          variance = d;
        }
      }
      taken.push_back({channel, {value, variance}});
    }
  }
  std::sort(taken.begin(), taken.end(),
            [](const auto& x, const auto& y) { return x.first < y.first; });
  const auto n = static_cast<Eigen::Index>(taken.size());
  out.reading.values.resize(n);
  out.reading.variances.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    out.reading.channels.push_back(taken[static_cast<std::size_t>(i)].first);
    out.reading.values[i] = taken[static_cast<std::size_t>(i)].second.first;
    out.reading.variances[i] = taken[static_cast<std::size_t>(i)].second.second;
  }
  return out;
}

sensor_msgs::Imu imuFromMeasurement(const Measurement& m, const ros::Time& stamp,
                                    const ImuChannels& ch, const std::vector<double>& variances) {
  sensor_msgs::Imu msg;
  msg.header.stamp = stamp;
  msg.orientation_covariance[0] = -1.0;  // no orientation estimate
  const auto valueOf = [&](int channel) {
    if (channel < 0) return kNaN;
    for (std::size_t i = 0; i < m.channels.size(); ++i) {
      if (m.channels[i] == channel) return m.values[static_cast<Eigen::Index>(i)];
    }
    return kNaN;
  };
  const auto varianceOf = [&](int channel) {
    return channel >= 0 && static_cast<std::size_t>(channel) < variances.size()
               ? variances[static_cast<std::size_t>(channel)]
               : 0.0;
  };
  msg.linear_acceleration.x = valueOf(ch.accel_x);
  msg.linear_acceleration.y = valueOf(ch.accel_y);
  msg.linear_acceleration.z = valueOf(ch.accel_z);
  msg.angular_velocity.x = valueOf(ch.gyro_x);
  msg.angular_velocity.y = valueOf(ch.gyro_y);
  msg.angular_velocity.z = valueOf(ch.gyro_z);
  const bool accel = ch.accel_x >= 0 || ch.accel_y >= 0 || ch.accel_z >= 0;
  const bool gyro = ch.gyro_x >= 0 || ch.gyro_y >= 0 || ch.gyro_z >= 0;
  if (!accel) {
    msg.linear_acceleration_covariance[0] = -1.0;
  } else {
    msg.linear_acceleration_covariance[0] = varianceOf(ch.accel_x);
    msg.linear_acceleration_covariance[4] = varianceOf(ch.accel_y);
    msg.linear_acceleration_covariance[8] = varianceOf(ch.accel_z);
  }
  if (!gyro) {
    msg.angular_velocity_covariance[0] = -1.0;
  } else {
    msg.angular_velocity_covariance[0] = varianceOf(ch.gyro_x);
    msg.angular_velocity_covariance[4] = varianceOf(ch.gyro_y);
    msg.angular_velocity_covariance[8] = varianceOf(ch.gyro_z);
  }
  return msg;
}

int odomSpeedChannel(const std::vector<std::string>& channel_names,
                     const std::vector<std::string>& selected) {
  return indexOf(channel_names, selected, "speed");
}

ImuConversion readingFromOdometry(const nav_msgs::Odometry& msg, int speed_channel) {
  ImuConversion out;
  out.reading.stamp_ns =
      static_cast<std::int64_t>(msg.header.stamp.sec) * 1000000000LL + msg.header.stamp.nsec;
  out.reading.values.resize(0);
  out.reading.variances.resize(0);
  if (speed_channel < 0) return out;
  const auto& cov = msg.twist.covariance;
  if (cov[0] == -1.0) {
    out.problems.push_back("twist.covariance[0] = -1: no twist data (speed not observed)");
    out.problem_kinds.push_back(ImuProblem::kNoData);
    return out;
  }
  const double value = msg.twist.twist.linear.x;
  if (!std::isfinite(value)) {
    out.problems.push_back("twist.twist.linear.x is " + std::to_string(value) + ": not observed");
    out.problem_kinds.push_back(ImuProblem::kNonFinite);
    return out;
  }
  double variance = kNaN;
  if (std::all_of(cov.begin(), cov.end(), [](double v) { return v == 0.0; })) {
    ++out.unknown_covariances;
  } else if (!std::isfinite(cov[0]) || cov[0] < 0.0) {
    out.problems.push_back("twist.covariance[0] = " + std::to_string(cov[0]) +
                           " is not a variance: measurement.sensor_std used");
    out.problem_kinds.push_back(ImuProblem::kBadCovariance);
  } else if (cov[0] > 0.0) {
    variance = cov[0];
  }
  out.reading.channels.push_back(speed_channel);
  out.reading.values = Eigen::VectorXd::Constant(1, value);
  out.reading.variances = Eigen::VectorXd::Constant(1, variance);
  return out;
}

nav_msgs::Odometry odometryFromMeasurement(const Measurement& m, const ros::Time& stamp,
                                           int speed_channel, double variance) {
  nav_msgs::Odometry msg;
  msg.header.stamp = stamp;
  msg.twist.twist.linear.x = kNaN;
  for (std::size_t i = 0; i < m.channels.size(); ++i) {
    if (m.channels[i] == speed_channel) msg.twist.twist.linear.x = m.values[static_cast<Eigen::Index>(i)];
  }
  if (variance > 0.0) msg.twist.covariance[0] = variance;
  return msg;
}

}  // namespace pc_ekf
