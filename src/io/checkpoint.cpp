#include "pc_ekf/io/checkpoint.h"

#include <algorithm>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>

#include "pc_ekf/io/atomic_file.h"
#include "pc_ekf/io/key_value_text.h"
#include "pc_ekf/io/number_text.h"

namespace pc_ekf {
namespace {

constexpr const char* kFormat = "pc_ekf_checkpoint 2";  // 2: road buffer
constexpr const char* kEnd = "end";
constexpr const char* kCounterPrefix = "counter.";

// ---- writing ----

std::string number(double v) { return roundTripText(v); }

std::string stampText(const CheckpointStamp& s) {
  return std::to_string(s.sec) + " " + std::to_string(s.nsec);
}

std::string matrixText(const Eigen::MatrixXd& m) {
  std::string s = std::to_string(m.rows()) + " " + std::to_string(m.cols());
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) s += " " + number(m(r, c));
  }
  return s;
}

std::string measurementText(const Measurement& m) {
  std::string s = number(m.time) + " " + std::to_string(m.channels.size());
  for (int c : m.channels) s += " " + std::to_string(c);
  for (Eigen::Index i = 0; i < m.values.size(); ++i) s += " " + number(m.values(i));
  return s;
}

void writeFilter(std::ostream& out, const std::string& name, const FilterCheckpoint& f) {
  out << name << ".time = " << number(f.time) << "\n";
  out << name << ".samples = " << f.samples << "\n";
  out << name << ".x = " << matrixText(f.x) << "\n";
  out << name << ".working = " << (f.working.size() > 0 ? matrixText(f.working) : "none") << "\n";
}

// ---- reading ----

[[noreturn]] void raiseCheckpointError(const std::string& message) {
  throw CheckpointError(message);
}

// The checkpoint's value kinds on top of the generic reader.
class CheckpointText : public KeyValueText {
 public:
  explicit CheckpointText(const std::string& path)
      : KeyValueText(path, "checkpoint", kEnd, raiseCheckpointError) {}

  CheckpointStamp stamp(const std::string& key) {
    const auto t = tokens(key);
    count(key, t, 2);
    return {static_cast<std::uint32_t>(whole(key, t[0], 0xffffffffu)),
            static_cast<std::uint32_t>(whole(key, t[1], 999999999u))};
  }
  Eigen::MatrixXd matrix(const std::string& key) { return matrix(key, tokens(key)); }
  Eigen::MatrixXd matrix(const std::string& key, const std::vector<std::string>& t) {
    if (t.size() < 2) fail(key, "expected 'rows cols' and the values, row-major");
    const auto rows = static_cast<Eigen::Index>(whole(key, t[0], 100000));
    const auto cols = static_cast<Eigen::Index>(whole(key, t[1], 100000));
    if (rows == 0 || cols == 0) fail(key, "empty matrix");
    count(key, t, 2 + static_cast<std::size_t>(rows * cols));
    Eigen::MatrixXd m(rows, cols);
    std::size_t i = 2;
    for (Eigen::Index r = 0; r < rows; ++r) {
      for (Eigen::Index c = 0; c < cols; ++c) m(r, c) = real(key, t[i++]);
    }
    return m;
  }
  Measurement measurement(const std::string& key) {
    const auto t = tokens(key);
    if (t.size() < 2) fail(key, "expected 'time channels ...'");
    Measurement m;
    m.time = real(key, t[0]);
    const auto n = static_cast<std::size_t>(whole(key, t[1], 1000));
    count(key, t, 2 + 2 * n);
    m.values.resize(static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i) {
      m.channels.push_back(static_cast<int>(whole(key, t[2 + i], 1000)));
      m.values(static_cast<Eigen::Index>(i)) = real(key, t[2 + n + i]);
    }
    return m;
  }
  FilterCheckpoint filter(const std::string& name) {
    FilterCheckpoint f;
    f.time = real(name + ".time");
    f.samples = integer(name + ".samples");
    f.x = matrix(name + ".x");
    const std::string working = name + ".working";
    const auto keys = remainingKeys();
    if (std::binary_search(keys.begin(), keys.end(), working)) {
      const auto t = tokens(working);
      if (!(t.size() == 1 && t[0] == "none")) f.working = matrix(working, t);
    }
    return f;
  }

  // Counters, then nothing may be left.
  std::map<std::string, std::uint64_t> counters() {
    std::map<std::string, std::uint64_t> out;
    for (const std::string& key : remainingKeys()) {
      if (key.rfind(kCounterPrefix, 0) != 0) fail(key, "unknown key");
      const auto t = tokens(key);
      count(key, t, 1);
      out[key.substr(std::strlen(kCounterPrefix))] =
          whole(key, t[0], std::numeric_limits<std::uint64_t>::max());
    }
    return out;
  }
};

}  // namespace

void writeCheckpoint(const Checkpoint& c, const std::string& path) {
  std::ostringstream out;
  out << "# estimator_node checkpoint (src/io/checkpoint.h); resumed when config_hash matches\n";
  out << "format = " << kFormat << "\n";
  out << "config_hash = " << hashText(c.config_hash) << "\n";
  out << "road_mode = " << c.road_mode << "\n";
  out << "origin = " << stampText(c.origin) << "\n";
  out << "last_sample = " << stampText(c.last_sample) << "\n";
  writeFilter(out, "full", c.full);
  writeFilter(out, "decimated", c.decimated);
  out << "coherence_disagreement = ";
  if (c.coherence_disagreement) {
    const Eigen::VectorXd& d = *c.coherence_disagreement;
    out << d.size();
    for (Eigen::Index i = 0; i < d.size(); ++i) out << " " << number(d(i));
    out << "\n";
  } else {
    out << "none\n";
  }
  out << "batch.samples = " << c.batch_samples.size() << "\n";
  out << "batch.last_stamp = " << stampText(c.batch_last_stamp) << "\n";
  for (std::size_t i = 0; i < c.batch_samples.size(); ++i) {
    out << "batch." << i << " = " << measurementText(c.batch_samples[i]) << "\n";
  }
  out << "road.samples = " << c.road.t.size() << "\n";
  out << "road.last_stamp = " << stampText(c.road_last_stamp) << "\n";
  for (std::size_t i = 0; i < c.road.t.size(); ++i) {
    out << "road." << i << " = " << number(c.road.t[i]);
    for (const auto& column : c.road.heights) out << " " << number(column[i]);
    out << "\n";
  }
  for (const auto& [name, value] : c.counters) {
    out << kCounterPrefix << name << " = " << value << "\n";
  }
  out << kEnd << " = " << c.full.samples << "\n";
  const std::string text = out.str();

  try {
    writeFileAtomically(path, text);
  } catch (const AtomicWriteError& e) {
    throw CheckpointError("checkpoint " + path + ": " + e.what());
  }
}

void writeCheckpoint(const CheckpointSnapshot& s, const std::string& path) {
  Checkpoint c = s.checkpoint;
  c.batch_samples = s.batch.series();
  writeCheckpoint(c, path);
}

Checkpoint readCheckpoint(const std::string& path) {
  CheckpointText f(path);
  Checkpoint c;
  {
    const auto t = f.tokens("format");
    std::string format;
    for (const auto& w : t) format += (format.empty() ? "" : " ") + w;
    if (format != kFormat) f.fail("format", "'" + format + "', expected '" + kFormat + "'");
  }
  const std::string hash = f.text("config_hash");
  char* end = nullptr;
  c.config_hash = std::strtoull(hash.c_str(), &end, 16);
  if (hash.size() != 18 || hash.rfind("0x", 0) != 0 || *end != '\0') {
    f.fail("config_hash", "'" + hash + "' is not 0x and 16 hex digits");
  }
  c.road_mode = f.text("road_mode");
  if (c.road_mode != "analytic" && c.road_mode != "topic") {
    f.fail("road_mode", "'" + c.road_mode + "', expected analytic or topic");
  }
  c.origin = f.stamp("origin");
  c.last_sample = f.stamp("last_sample");
  c.full = f.filter("full");
  if (f.endValue() != std::to_string(c.full.samples)) {
    f.fail("the 'end' line (" + f.endValue() + ") does not repeat full.samples (" +
           std::to_string(c.full.samples) + "): truncated or edited");
  }
  c.decimated = f.filter("decimated");
  if (c.decimated.x.rows() != c.full.x.rows() || c.decimated.x.cols() != c.full.x.cols()) {
    f.fail("decimated.x", "size differs from full.x");
  }
  {
    const auto words = f.tokens("coherence_disagreement");
    if (!(words.size() == 1 && words[0] == "none")) {
      // 'n' and n values
      const auto n = static_cast<std::size_t>(f.whole("coherence_disagreement", words[0], 1000));
      f.count("coherence_disagreement", words, 1 + n);
      Eigen::VectorXd d(static_cast<Eigen::Index>(n));
      for (std::size_t i = 0; i < n; ++i) {
        d(static_cast<Eigen::Index>(i)) = f.real("coherence_disagreement", words[1 + i]);
      }
      c.coherence_disagreement = d;
    }
  }
  const int batch = f.integer("batch.samples");
  c.batch_last_stamp = f.stamp("batch.last_stamp");
  for (int i = 0; i < batch; ++i) {
    c.batch_samples.push_back(f.measurement("batch." + std::to_string(i)));
  }
  const int road = f.integer("road.samples");
  c.road_last_stamp = f.stamp("road.last_stamp");
  for (int i = 0; i < road; ++i) {
    const std::string key = "road." + std::to_string(i);
    const auto t = f.tokens(key);
    // t and one height per contact: as many as the first road sample has.
    if (i == 0 && t.size() < 2) f.count(key, t, 3);
    if (i == 0) c.road.heights.resize(t.size() - 1);
    f.count(key, t, c.road.heights.size() + 1);
    const double time = f.real(key, t[0]);
    if (i > 0 && !(time > c.road.t.back())) f.fail(key, "time not after the previous road sample");
    c.road.t.push_back(time);
    for (std::size_t k = 0; k < c.road.heights.size(); ++k) c.road.heights[k].push_back(f.real(key, t[k + 1]));
  }
  if (road > 0 && c.road_mode != "topic") f.fail("road.samples", "road samples with road_mode analytic");
  c.counters = f.counters();
  return c;
}

void requireConfigHash(const Checkpoint& c, std::uint64_t current, const std::string& path) {
  if (c.config_hash == current) return;
  throw CheckpointError("checkpoint " + path + " was written under config hash " +
                        hashText(c.config_hash) + ", the current config hashes to " +
                        hashText(current) +
                        ": the configuration changed, so the saved filter state does not apply "
                        "(restore that configuration, or delete the checkpoint to start from "
                        "the prior)");
}

}  // namespace pc_ekf
