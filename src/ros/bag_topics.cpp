#include "pc_ekf/ros/bag_topics.h"

#include <iomanip>
#include <sstream>

namespace pc_ekf {
namespace bag_topics {

std::int64_t nanoseconds(const ros::Time& t) {
  return static_cast<std::int64_t>(t.sec) * 1000000000LL + t.nsec;
}

std::string stampText(const ros::Time& t) {
  std::ostringstream o;
  o << t.sec << "." << std::setw(9) << std::setfill('0') << t.nsec;
  return o.str();
}

std::string join(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s.empty() ? "none" : s;
}

Measurement mergeStampGroup(const std::string& path, StampedSample* begin, StampedSample* end,
                            int channels) {
  // A sample alone at its stamp with its channels in order is moved as it
  // is (the record is not held twice).
  Measurement& first = begin->m;
  if (end - begin == 1 && std::adjacent_find(first.channels.begin(), first.channels.end(),
                                             std::greater_equal<int>()) == first.channels.end()) {
    Measurement alone;
    alone.time = first.time;
    alone.channels = std::move(first.channels);
    alone.values = std::move(first.values);
    return alone;
  }
  std::vector<double> values(static_cast<std::size_t>(channels), 0.0);
  std::vector<bool> seen(static_cast<std::size_t>(channels), false);
  for (StampedSample* s = begin; s != end; ++s) {
    const Measurement& m = s->m;
    for (std::size_t k = 0; k < m.channels.size(); ++k) {
      const int c = m.channels[k];
      if (seen[static_cast<std::size_t>(c)]) {
        throw BagError(path + ": two suspension/joint_states messages stamped " +
                       stampText(begin->stamp) + " both observe channel " + std::to_string(c) +
                       (channels == 4 ? " (u1, u2, v1, v2 = 0..3)" : ""));
      }
      seen[static_cast<std::size_t>(c)] = true;
      values[static_cast<std::size_t>(c)] = m.values(static_cast<Eigen::Index>(k));
    }
  }
  Measurement merged;
  merged.time = first.time;
  std::vector<double> kept;
  for (int c = 0; c < channels; ++c) {
    if (!seen[static_cast<std::size_t>(c)]) continue;
    merged.channels.push_back(c);
    kept.push_back(values[static_cast<std::size_t>(c)]);
  }
  merged.values = Eigen::Map<const Eigen::VectorXd>(kept.data(), static_cast<Eigen::Index>(kept.size()));
  return merged;
}

}  // namespace bag_topics
}  // namespace pc_ekf
