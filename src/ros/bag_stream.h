// A road-free bag (BagReadOptions::road_free) read as a stream: the samples
// readBag would give, one at a time in stamp order, each aligned with the
// IMU and odometry readings as readBag aligns them (imu_alignment.h: a
// sample is aligned once a reading at or after its stamp is in), so the
// memory needed does not grow with the record.
#pragma once

#include <memory>
#include <string>

#include "pc_ekf/io/record_stream.h"
#include "pc_ekf/ros/bag_io.h"

namespace pc_ekf {

// read() returns false (the caller reads the bag whole with readBag) for a
// bag with a road, one whose joint_states stamps are not in bag order
// (readBag sorts them), and on the first pass for any bag readBag would
// refuse: readBag then gives today's error. The warnings are readBag's.
std::unique_ptr<RecordStream> bagRecordStream(const std::string& path,
                                              const BagReadOptions& options);

}  // namespace pc_ekf
