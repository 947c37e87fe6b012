// synthesize_bag: simulates the truth model of a config and writes a bag in
// the layout of docs/method.md §8.2 (road/profile, suspension/joint_states,
// ground_truth) and, with --csv, the same measurements as CSV. Exit 2 with a
// one-line reason on bad input.
#include <cmath>
#include <fstream>
#include <iostream>
#include <string>

#include "pc_ekf/filter/synthetic_data.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/ros/bag_io.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/ros/model_plugins.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/pc/polynomial_basis.h"
#include "pc_ekf/ros/message_conversion.h"
#include "pc_ekf/tools/command_line.h"

namespace {

const char* kUsage =
    "usage: synthesize_bag --config FILE.yaml --output FILE.bag [--seed N]\n"
    "                      [--road-rate HZ (1000)] [--start-time SEC (1000000000)]\n"
    "                      [--csv FILE.csv] [--imu-rate HZ] [--imu-offset SEC (0)]\n"
    "Writes road/profile at HZ from t = 0 to the last sample, suspension/joint_states\n"
    "at the config's sample times and ground_truth, stamped START + t (with a\n"
    "truth.schedule also one ground_truth per sample, at its stamp). When\n"
    "measurement.channels select IMU channels, sensor_msgs/Imu on imu/data: at the\n"
    "sample times, or with --imu-rate at IMU-OFFSET + k / HZ (k >= 0, t > 0) through\n"
    "one IMU period past the last sample, simulated at those times (covariances all\n"
    "zero: \"unknown\"); gyro_z is angular_velocity.z. When they select speed,\n"
    "nav_msgs/Odometry on odom at the sample times (twist.twist.linear.x, covariance\n"
    "all zero). The values are the model's in measurement.zero's convention.\n";

// Parses a finite double; false when the whole text is not one.
bool parseDouble(const std::string& text, double* value) {
  try {
    std::size_t used = 0;
    *value = std::stod(text, &used);
    return used == text.size() && std::isfinite(*value);
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pc_ekf;
  CommandLine args("synthesize_bag", kUsage);
  const int parsed = args.parse(
      argc, argv, {"--config", "--output", "--seed", "--road-rate", "--start-time", "--csv", "--imu-rate",
                 "--imu-offset"});
  if (parsed >= 0) return parsed;
  if (!args.has("--config")) return args.badInput(std::string("--config is required\n") + kUsage);
  if (!args.has("--output")) return args.badInput(std::string("--output is required\n") + kUsage);

  double road_rate = 1000.0;
  if (args.has("--road-rate") &&
      (!parseDouble(args["--road-rate"], &road_rate) || road_rate <= 0.0 || road_rate > 1e6)) {
    return args.badInput("--road-rate '" + args["--road-rate"] + "' is not a rate in (0, 1e6] Hz");
  }
  double start_time = 1.0e9;
  if (args.has("--start-time") && (!parseDouble(args["--start-time"], &start_time) ||
                                     start_time <= 0.0 || start_time > 4.0e9)) {
    return args.badInput("--start-time '" + args["--start-time"] +
                    "' is not a time in (0, 4e9] s (ros::Time must stay positive)");
  }

  double imu_rate = 0.0, imu_offset = 0.0;
  if (args.has("--imu-rate") &&
      (!parseDouble(args["--imu-rate"], &imu_rate) || imu_rate <= 0.0 || imu_rate > 1e5)) {
    return args.badInput("--imu-rate '" + args["--imu-rate"] + "' is not a rate in (0, 1e5] Hz");
  }
  if (args.has("--imu-offset") &&
      (!parseDouble(args["--imu-offset"], &imu_offset) || std::abs(imu_offset) > 1.0)) {
    return args.badInput("--imu-offset '" + args["--imu-offset"] +
                         "' is not a time in [-1, 1] s");
  }
  if (args.has("--imu-offset") && !args.has("--imu-rate")) {
    return args.badInput("--imu-offset needs --imu-rate (without it the IMU shares the samples' stamps)");
  }

  return args.run([&] {
    const EstimatorConfig config = loadConfigFile(args["--config"], modelRegistryWithPlugins());
    std::uint64_t seed = config.truth.seed;
    int status = 0;
    if (args.has("--seed") && !args.unsignedValue("--seed", &seed, &status)) return status;
    if (config.road.source == RoadSource::kTopic) {
      return args.badInput(config.source +
                      ": key 'road.source' is topic; synthesize_bag needs an analytic or series "
                      "road to simulate");
    }
    // Road-free (road.source none): the truth drives truth.road, and the bag
    // holds no road, as a vehicle's recording would.
    const bool road_free = config.road.source == RoadSource::kNone;
    const auto road = road_free ? makeTruthRoad(config) : makeRoad(config);
    const auto model = road_free ? truthOnItsRoad(config) : makeModel(config, road);
    const MeasurementSeries samples = synthesizeFromConfig(config, *model, seed);
    if (samples.empty()) return args.badInput(config.source + ": the config gives no samples");

    BagContents bag;
    bag.origin = timeFromSeconds(start_time);
    // Road from t = 0 through the last sample (the last road time >= it).
    const double t_last = samples.back().time;
    const long count = static_cast<long>(std::ceil(t_last * road_rate - 1e-9)) + 1;
    if (!road_free && count > 50000000L) {
      return args.badInput("--road-rate " + args["--road-rate"] + " gives " + std::to_string(count) +
                      " road messages over " + std::to_string(t_last) + " s; too many");
    }
    if (!road_free) bag.road_contacts = sampleContactRoad(*road, t_last, road_rate);
    if (!config.model_type->twoContacts()) {
      bag.contacts = config.model_type->contactNames();
      bag.joints = suspensionJoints(*config.model_type, config.node.joint_names);
    }
    bag.samples = samples;
    bag.imu = imuChannels(config.model_type->channelNames(), config.measurement.channels);
    // speed: odom messages (twist.linear.x) at the sample times.
    bag.odom_speed = odomSpeedChannel(config.model_type->channelNames(), config.measurement.channels);
    if (bag.odom_speed >= 0) {
      std::vector<int> other;
      for (int c : channelIndices(config)) {
        if (c != bag.odom_speed) other.push_back(c);
      }
      bag.odom_samples = onlyChannels(samples, {bag.odom_speed});
      bag.samples = onlyChannels(samples, other);
    }
    if (bag.imu.any()) {
      std::vector<int> imu, other;
      for (int c : channelIndices(config)) {
        if (c == bag.odom_speed) continue;
        (bag.imu.has(c) ? imu : other).push_back(c);
      }
      bag.samples = onlyChannels(samples, other);
      if (imu_rate <= 0.0) {
        bag.imu_samples = onlyChannels(samples, imu);
      } else {
        const auto truth = truthModel(config, *model);
        SyntheticDataSettings s = syntheticSettings(config, *truth, seed + 1);
        s.times.clear();
        const double period = 1.0 / imu_rate;
        for (long k = 0;; ++k) {
          const double t = imu_offset + static_cast<double>(k) * period;
          if (t > t_last + period) break;
          if (t > 0.0) s.times.push_back(t);
        }
        s.channels = imu;
        s.timing = TimingImperfections{};
        bag.imu_samples = synthesizeMeasurements(*truth, truthParameters(config, *model), s);
      }
    }

    const ParameterMapping mapping(*model, config.uncertain);
    const PolynomialBasis basis(mapping.germs(), config.pc_order, config.pc_truncation);
    bag.ground_truth = groundTruthMessage(mapping, truthXiAt(config, 0.0), &basis, bag.origin);
    // A truth that changes: also one ground truth per sample, at its stamp
    // (writeBag makes them from one message per change); the values only, the
    // PC basis is in the first one (a 16-parameter basis would be 14 kB a sample).
    if (!config.truth.schedule.empty()) {
      std::vector<double> times = {0.0};
      for (const auto& ch : config.truth.schedule) times.push_back(ch.time);
      for (double t : times) {
        ParameterEstimate m = groundTruthMessage(mapping, truthXiAt(config, t), nullptr, bag.origin);
        m.time = t;
        bag.ground_truth_changes.push_back(std::move(m));
      }
    }

    writeBag(args["--output"], bag);
    if (args.has("--csv")) {
      std::ofstream csv(args["--csv"]);
      if (!csv) return args.badInput(args["--csv"] + ": cannot open for writing");
      writeMeasurementCsv(csv, samples, config.model_type->channelNames());
      csv.flush();
      if (!csv) return args.badInput(args["--csv"] + ": write failed");
    }
    std::cerr << "synthesize_bag: wrote " << args["--output"] << " (" << samples.size()
              << " samples, ";
    if (road_free) {
      std::cerr << "no road (road.source none) over " << t_last;
    } else {
      std::cerr << count << " road messages at " << road_rate << " Hz over " << t_last;
    }
    std::cerr << " s, seed " << seed;
    if (!bag.imu_samples.empty()) std::cerr << ", " << bag.imu_samples.size() << " imu/data messages";
    if (!bag.odom_samples.empty()) std::cerr << ", " << bag.odom_samples.size() << " odom messages";
    std::cerr << ")\n";
    return 0;
  });
}
