// config/vehicle_imu.yaml for a vehicle without heights or an anti-roll bar,
// driven straight without odometry (the paper's body, as long_drive.yaml):
// the load's height, the bar and the two heights out with their tolerances
// and walks, and the speed and yaw-rate channels out. For the tests of the
// long-drive machinery, measured on that vehicle.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace pc_ekf {

inline YAML::Node vehicleImuWithoutHeights() {
  YAML::Node root = YAML::LoadFile(std::string(PC_EKF_SOURCE_DIR) + "/config/vehicle_imu.yaml");
  YAML::Node uncertain;
  for (std::size_t i = 0; i < 2; ++i) uncertain.push_back(root["uncertain"][i]);
  root["uncertain"] = uncertain;
  for (const char* name : {"anti_roll_bar", "body_cg_height", "imu_height"}) {
    root["vehicle"][name] = 0.0;
    root["tolerances"].remove(name);
  }
  // The walks: uncertain (M, d_CG, h_M), then the tolerances, the last three these.
  YAML::Node drift;
  const YAML::Node walk = root["filter"]["drift_relative"];
  for (std::size_t i = 0; i + 3 < walk.size(); ++i) {
    if (i != 2) drift.push_back(walk[i]);
  }
  root["filter"]["drift_relative"] = drift;
  // speed and gyro_z: the last two channels.
  YAML::Node m = root["measurement"];
  for (const char* key : {"channels", "sensor_std", "r_relative", "noise_relative"}) {
    YAML::Node cut;
    for (std::size_t i = 0; i + 2 < m[key].size(); ++i) cut.push_back(m[key][i]);
    m[key] = cut;
  }
  YAML::Node floor;
  const YAML::Node truth_floor = root["truth"]["sensor"]["noise_floor"];
  for (std::size_t i = 0; i + 2 < truth_floor.size(); ++i) floor.push_back(truth_floor[i]);
  root["truth"]["sensor"]["noise_floor"] = floor;
  root["collocation"]["points"] = 124;  // twice the basis terms at n = 16
  root["collocation"]["batch_points"] = 306;
  return root;
}

}  // namespace pc_ekf
