#include "pc_ekf/io/estimator_config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "pc_ekf/reference/posterior_coarse_grid.h"
#include "pc_ekf/io/config_identity.h"
#include "pc_ekf/io/tolerances.h"
#include "pc_ekf/io/vehicle_file.h"
#include "pc_ekf/io/vehicle_section.h"
#include "pc_ekf/io/yaml_reader.h"
#include "pc_ekf/pc/polynomial_basis.h"

namespace pc_ekf {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<UncertainParameter> readUncertain(YamlMapReader& root, const ModelType& type,
                                              const ModelParameters& parameters) {
  std::vector<UncertainParameter> out;
  const YAML::Node seq = root.sequence("uncertain");
  if ((!seq.IsDefined() || seq.IsNull() || seq.size() == 0) && !root.has("tolerances")) {
    root.fail("uncertain", "(empty)",
              "a list of at least one uncertain parameter (or tolerances: on model values)");
  }
  if (!seq.IsDefined() || seq.IsNull()) return out;
  const auto& names = type.parameterNames();
  const Eigen::VectorXd& values = parameters.values;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    YamlMapReader r(seq[i], root.keyPath("uncertain[" + std::to_string(i) + "]"), root.source());
    UncertainParameter u;
    r.text("name", u.name);
    const auto it = std::find(names.begin(), names.end(), u.name);
    if (it == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      r.fail("name", "'" + u.name + "'", "one of " + list);
    }
    if (!seen.insert(u.name).second) r.fail("name", "'" + u.name + "'", "each parameter once");
    u.nominal = values[it - names.begin()];
    r.number("nominal", u.nominal, -kInf, kInf);
    r.number("relative_range", u.relative_range, 0.0, kInf, true);
    if (!r.has("relative_range")) {  // 0 would be a parameter fixed at its nominal
      r.fail("relative_range", "(absent)",
             "the prior's relative half-width, > 0 (value = nominal (1 + relative_range xi))");
    }
    u.germ = readGermSpec(r.map("germ"));
    r.finish();
    out.push_back(u);
  }
  return out;
}

void readSpeedBump(YamlMapReader& b, SpeedBumpSettings& s) {
  b.number("speed_kmh", s.speed_kmh, 0.0, kInf, true);
  b.number("height_left", s.height_left, -kInf, kInf);
  b.number("height_right", s.height_right, -kInf, kInf);
  b.number("ramp_up_length", s.ramp_up_length, 0.0, kInf, true);
  b.number("flat_length", s.flat_length, 0.0, kInf);
  b.number("ramp_down_length", s.ramp_down_length, 0.0, kInf, true);
  b.number("delay_fraction", s.delay_fraction, 0.0, kInf);
  b.number("start_distance", s.start_distance, 0.0, kInf);
}

void readSine(YamlMapReader& n, SineSettings& s) {
  n.number("amplitude", s.amplitude, -kInf, kInf);
  n.number("frequency", s.frequency, 0.0, kInf, true);
  n.number("right_sign", s.right_sign, -1.0, 1.0);
}

// An ISO 8608 class key: one letter A..E.
void readIsoClass(YamlMapReader& r, char& road_class) {
  std::string text(1, road_class);
  r.text("class", text);
  if (text.size() != 1 || text[0] < 'A' || text[0] > 'E') {
    r.fail("class", "'" + text + "'", "A, B, C, D or E (ISO 8608)");
  }
  road_class = text[0];
}

// A manoeuvre segment's keys (turn, lane_change, slalom: road_input.h's
// ManoeuvreSettings), driven at speed_kmh on a flat road, on an ISO 8608 one
// (surface: iso8608, with an iso8608 segment's keys and defaults) or on a
// measured profile (surface: profile: file, default road.profile.file; start).
void readManoeuvre(YamlMapReader& e, const RoadConfig& road, std::size_t index,
                   CourseSegment& seg) {
  ManoeuvreSettings& m = seg.manoeuvre;
  seg.speed_kmh = road.speed_kmh;
  if (seg.isLongitudinal()) {
    // brake: deceleration, accelerate: acceleration (m/s^2, > 0), from
    // speed_kmh (an acceleration may start from a standstill).
    e.number("speed_kmh", seg.speed_kmh, 0.0, 1000.0, seg.type == CourseSegment::Type::kBrake);
    e.number(seg.type == CourseSegment::Type::kBrake ? "deceleration" : "acceleration",
             m.longitudinal, 0.0, kInf, true);
  } else {
    e.number("speed_kmh", seg.speed_kmh, 0.0, 1000.0, true);
    e.number("lateral_acceleration", m.lateral_acceleration, -kInf, kInf);
  }
  if (seg.type == CourseSegment::Type::kTurn) {
    e.number("radius", m.radius, -kInf, kInf);
    e.number("ramp", m.ramp, 0.0, kInf);
  }
  if (seg.type == CourseSegment::Type::kSlalom) e.number("frequency", m.frequency, 0.0, kInf, true);
  std::string surface = "flat";
  e.text("surface", surface);
  if (surface != "flat" && surface != "iso8608" && surface != "profile") {
    e.fail("surface", "'" + surface + "'", "flat, iso8608 or profile");
  }
  if (surface == "profile") {
    std::string file = road.profile_file;
    e.text("file", file);
    if (file.empty()) {
      e.fail("file", "(empty)", "a road profile CSV path (s,left,right in m) for surface profile");
    }
    e.number("start", m.profile_start, 0.0, kInf);
    try {
      m.measured = readMeasuredProfileCsv(file);
    } catch (const std::invalid_argument& ex) {
      e.fail("file", "'" + file + "'", std::string("a readable road profile: ") + ex.what());
    }
    return;
  }
  m.rough = surface == "iso8608";
  if (!m.rough) return;
  seg.iso8608 = road.iso8608;
  seg.iso8608.seed = road.iso8608.seed + index;  // mod 2^64
  if (!(road.iso8608.lead_in > 0.0)) {
    e.fail("surface", "iso8608", "road.iso8608.lead_in > 0 (the road blends in over it)");
  }
  readIsoClass(e, seg.iso8608.road_class);
  e.unsignedInteger("seed", seg.iso8608.seed);
  e.number("correlation", seg.iso8608.correlation, 0.0, 1.0);
}

// Segments default to the road.speed_bump / road.sine settings; an iso8608
// segment to road.iso8608 and road.speed_kmh, its seed to road.iso8608.seed
// plus its index in the course (so that segments are not copies).
std::vector<CourseSegment> readCourse(YamlMapReader& r, const RoadConfig& road) {
  std::vector<CourseSegment> out;
  const YAML::Node seq = r.sequence("course");
  if (!seq.IsDefined() || seq.IsNull()) return out;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    YamlMapReader e(seq[i], r.keyPath("course[" + std::to_string(i) + "]"), r.source());
    CourseSegment seg;
    std::string type;
    e.text("type", type);
    const auto duration = [&] {
      if (!e.has("duration")) e.fail("duration", "(empty)", "a positive duration in s");
      e.number("duration", seg.duration, 0.0, kInf, true);
    };
    if (type == "speed_bump") {
      seg.type = CourseSegment::Type::kSpeedBump;
      seg.speed_bump = road.speed_bump;
      readSpeedBump(e, seg.speed_bump);
    } else if (type == "sine" || type == "rest") {
      seg.type = type == "sine" ? CourseSegment::Type::kSine : CourseSegment::Type::kRest;
      seg.sine = road.sine;
      if (type == "sine") readSine(e, seg.sine);
      duration();
    } else if (type == "iso8608") {
      seg.type = CourseSegment::Type::kIso8608;
      seg.iso8608 = road.iso8608;
      seg.iso8608.seed = road.iso8608.seed + i;  // mod 2^64
      seg.speed_kmh = road.speed_kmh;
      if (!(road.iso8608.lead_in > 0.0)) {
        r.fail("iso8608.lead_in", "0",
               "a lead-in > 0 m when the course has iso8608 segments (each blends from the "
               "heights it starts at over it)");
      }
      e.number("speed_kmh", seg.speed_kmh, 0.0, 1000.0, true);
      readIsoClass(e, seg.iso8608.road_class);
      e.unsignedInteger("seed", seg.iso8608.seed);
      e.number("correlation", seg.iso8608.correlation, 0.0, 1.0);
      duration();
    } else if (type == "turn" || type == "lane_change" || type == "slalom" || type == "brake" ||
               type == "accelerate") {
      seg.type = type == "turn"          ? CourseSegment::Type::kTurn
                 : type == "lane_change" ? CourseSegment::Type::kLaneChange
                 : type == "slalom"      ? CourseSegment::Type::kSlalom
                 : type == "brake"       ? CourseSegment::Type::kBrake
                                         : CourseSegment::Type::kAccelerate;
      readManoeuvre(e, road, i, seg);
      duration();
    } else {
      e.fail("type", "'" + type + "'",
             "speed_bump, sine, rest, iso8608, turn, lane_change, slalom, brake or accelerate");
    }
    e.finish();
    out.push_back(seg);
  }
  return out;
}

RoadConfig readRoad(YamlMapReader r) {
  RoadConfig road;
  std::string source = toString(road.source);
  r.text("source", source);
  if (source == "speed_bump") road.source = RoadSource::kSpeedBump;
  else if (source == "sine") road.source = RoadSource::kSine;
  else if (source == "series") road.source = RoadSource::kSeries;
  else if (source == "topic") road.source = RoadSource::kTopic;
  else if (source == "course") road.source = RoadSource::kCourse;
  else if (source == "iso8608") road.source = RoadSource::kIso8608;
  else if (source == "profile") road.source = RoadSource::kProfile;
  else if (source == "none") road.source = RoadSource::kNone;
  else r.fail("source", "'" + source + "'",
              "speed_bump, sine, series, topic, course, iso8608, profile or none");
  r.number("speed_kmh", road.speed_kmh, 0.0, 1000.0, true);

  YamlMapReader iso = r.map("iso8608");
  readIsoClass(iso, road.iso8608.road_class);
  iso.unsignedInteger("seed", road.iso8608.seed);
  iso.number("correlation", road.iso8608.correlation, 0.0, 1.0);
  iso.number("lead_in", road.iso8608.lead_in, 0.0, 1e6);
  iso.number("n_min", road.iso8608.n_min, 0.0, 1e3, true);
  iso.number("n_max", road.iso8608.n_max, road.iso8608.n_min, 1e3, true);
  iso.integer("bands", road.iso8608.bands, 1, 100000);
  iso.finish();

  YamlMapReader pf = r.map("profile");
  pf.text("file", road.profile_file);
  pf.finish();
  if (road.source == RoadSource::kProfile && road.profile_file.empty()) {
    pf.fail("file", "(empty)", "a road profile CSV path (s,left,right in m) when road.source is profile");
  }

  YamlMapReader b = r.map("speed_bump");
  readSpeedBump(b, road.speed_bump);
  b.finish();

  YamlMapReader n = r.map("sine");
  readSine(n, road.sine);
  n.finish();

  YamlMapReader f = r.map("series");
  f.text("file", road.series_file);
  f.finish();
  if (road.source == RoadSource::kSeries && road.series_file.empty()) {
    f.fail("file", "(empty)", "a road CSV path (t,y1,y2) when road.source is series");
  }
  road.course = readCourse(r, road);
  if (road.source == RoadSource::kCourse && road.course.empty()) {
    r.fail("course", "(empty)", "a list of segments when road.source is course");
  }
  r.finish();
  return road;
}

std::size_t basisSize(int n, int p, const BasisTruncation& truncation) {
  if (truncation.kind == TruncationKind::kHyperbolic || truncation.single_from >= 0) {
    return n < 1 ? 1 : truncatedMultiIndices(n, p, truncation).size();
  }
  double s = 1.0;  // C(n + p, p)
  for (int i = 1; i <= p; ++i) s = s * (n + i) / i;
  return static_cast<std::size_t>(std::llround(s));
}

BasisTruncation readTruncation(YamlMapReader& pc) {
  BasisTruncation t;
  std::string kind = toString(t.kind);
  pc.text("truncation", kind);
  try {
    t.kind = truncationKindFromString(kind);
  } catch (const std::invalid_argument&) {
    pc.fail("truncation", "'" + kind + "'", "total_degree or hyperbolic");
  }
  if (pc.has("q_norm") && t.kind != TruncationKind::kHyperbolic) {
    pc.fail("q_norm", "(set)", "no q_norm unless pc.truncation is hyperbolic");
  }
  t.q_norm = t.kind == TruncationKind::kHyperbolic ? 0.5 : 1.0;
  pc.number("q_norm", t.q_norm, 0.0, 1.0, true);
  return t;
}

bool readFlag(YamlMapReader& r, const std::string& key, bool value);

void readSafeguards(YamlMapReader& f, EstimatorConfig& c) {
  SafeguardSettings& s = c.safeguards;
  std::string support = toString(s.support);
  f.text("support", support);
  try {
    s.support = supportRuleFromString(support);
  } catch (const std::invalid_argument&) {
    f.fail("support", "'" + support + "'", "damp or ignore");
  }
  const std::size_t n = c.uncertain.size(), loads = c.loadCount();
  // One number per uncertain parameter: the loads', or all with the tolerances.
  const auto perParameter = [&](const std::string& key, const std::string& each) {
    std::vector<double> v;
    f.numberList(key, v, 0, n);
    if (!v.empty() && v.size() != n && v.size() != loads) {
      f.fail(key, "a list of " + std::to_string(v.size()),
             each + " per uncertain parameter (" + std::to_string(loads) +
                 (n != loads ? ", or " + std::to_string(n) + " with the tolerances" : std::string()) +
                 ")");
    }
    return v;
  };
  std::vector<double> drift = perParameter("drift", "one random-walk intensity");
  drift.resize(drift.empty() ? 0 : n, 0.0);  // tolerances: vehicle values do not drift
  for (double d : drift) {
    if (!(d >= 0.0) || !std::isfinite(d)) f.fail("drift", std::to_string(d), "intensities >= 0");
  }
  // The same as fractions of each parameter's nominal (a vehicle_file's
  // values scale them), added in quadrature.
  const std::vector<double> relative = perParameter("drift_relative", "one fraction");
  const std::vector<double> absolute = drift;
  for (std::size_t i = 0; i < relative.size(); ++i) {
    const double r = relative[i];
    if (!(r >= 0.0) || !std::isfinite(r)) f.fail("drift_relative", std::to_string(r), "fractions >= 0");
    if (r == 0.0) continue;
    drift.resize(n, 0.0);
    drift[i] = std::hypot(drift[i], r * std::abs(c.uncertain[i].nominal));
  }
  s.drift = Eigen::Map<const Eigen::VectorXd>(drift.data(), static_cast<Eigen::Index>(drift.size()));
  if (drift != absolute) {  // a relative share: not while standing
    s.drift_standing = Eigen::VectorXd::Zero(s.drift.size());
    s.drift_standing.head(static_cast<Eigen::Index>(absolute.size())) =
        Eigen::Map<const Eigen::VectorXd>(absolute.data(), static_cast<Eigen::Index>(absolute.size()));
  }
  YamlMapReader r = f.map("reopen");
  std::string mode = toString(s.reopen.mode);
  r.text("mode", mode);
  try {
    s.reopen.mode = reopenModeFromString(mode);
  } catch (const std::invalid_argument&) {
    r.fail("mode", "'" + mode + "'", "off, width, prior or load");
  }
  r.number("width", s.reopen.width, 0.0, kInf, true);
  r.integer("after", s.reopen.after, 1, 100000000);
  r.finish();
  std::string linearization = s.horizon.window > 0.0 ? "mean" : "collocation";
  f.text("linearization", linearization);
  if (linearization != "mean" && linearization != "collocation") {
    f.fail("linearization", "'" + linearization + "'", "collocation or mean");
  }
  YamlMapReader w = f.map("horizon");
  double window = 2.0;
  w.number("window", window, 0.0, kInf, true);
  w.number("shift", s.horizon.shift, 0.0, kInf, true);
  w.integer("reruns", s.horizon.reruns, 0, 100);
  w.number("step", s.horizon.step, 0.0, 0.1, true);
  w.number("clock_offset", s.horizon.clock_offset, 0.0, 1.0);
  w.number("cross_fall", s.horizon.cross_fall, 0.0, 0.5);
  w.number("cross_fall_walk", s.horizon.cross_fall_walk, 0.0, 1.0);
  w.number("accel_bias", s.horizon.accel_bias, 0.0, 10.0);
  w.number("gyro_bias", s.horizon.gyro_bias, 0.0, 1.0);
  std::string input_noise = s.horizon.input_noise_states ? "state" : "sample";
  w.text("input_noise", input_noise);
  if (input_noise != "state" && input_noise != "sample") {
    w.fail("input_noise", "'" + input_noise + "'", "sample or state");
  }
  s.horizon.input_noise_states = input_noise == "state";
  s.horizon.mass_scale_unobservable =
      readFlag(w, "mass_scale_unobservable", s.horizon.mass_scale_unobservable);
  w.finish();
  s.horizon.window = linearization == "mean" ? window : 0.0;
  if (s.reopen.mode == ReopenMode::kLoad && linearization != "mean") {
    r.fail("mode", "'load'", "filter.linearization: mean (or off, width, prior)");
  }
  YamlMapReader l = f.map("relinearize");
  RelinearizeSettings& rl = s.relinearize;
  l.number("shrink", rl.shrink, 0.0, 0.999);
  l.number("width", rl.width, 0.0, kInf, true);
  l.integer("max_restarts", rl.max_restarts, 1, 100);
  l.integer("max_samples", rl.max_samples, 1, 100000000);
  l.number("defer", rl.defer, 0.0, 1000.0);
  rl.prior_correction = readFlag(l, "prior_correction", rl.prior_correction);
  const SettingBreach breach = relinearizeBreach(rl);
  if (breach.broken()) l.fail(breach.setting, breach.value, breach.needs);
  l.finish();
}

void readFilterSections(YamlMapReader& root, EstimatorConfig& c) {
  YamlMapReader f = root.map("filter");
  std::string update = toString(c.update);
  f.text("update", update);
  try {
    c.update = updateRuleFromString(update);
  } catch (const std::invalid_argument&) {
    f.fail("update", "'" + update + "'", "paper or square_root");
  }
  YamlMapReader e = f.map("es_mda");
  e.numberList("alphas", c.es_mda.alphas, 1, 100);
  double inv = 0.0;
  for (double a : c.es_mda.alphas) {
    if (!(a > 0.0)) e.fail("alphas", std::to_string(a), "positive inflation factors");
    inv += 1.0 / a;
  }
  if (std::abs(inv - 1.0) > 1e-9) {
    e.fail("alphas", "with sum(1/alpha) = " + std::to_string(inv), "sum(1/alpha) = 1");
  }
  e.integer("restarts", c.es_mda.restarts, 0, 100);
  e.number("width", c.es_mda.width, BatchRestarts::kMinWidth, kInf, true);
  std::string covariance = c.es_mda.local_covariance ? "local" : "passes";
  e.text("covariance", covariance);
  if (covariance != "passes" && covariance != "local") {
    e.fail("covariance", "'" + covariance + "'", "passes or local");
  }
  c.es_mda.local_covariance = covariance == "local";
  e.finish();
  YamlMapReader k = f.map("enkf");
  k.integer("members", c.enkf.members, EnkfEnsemble::kMinMembers, 10000000);
  k.unsignedInteger("seed", c.enkf.seed);
  std::string enkf_update = c.enkf.square_root ? "square_root" : "perturbed";
  k.text("update", enkf_update);
  if (enkf_update != "perturbed" && enkf_update != "square_root") {
    k.fail("update", "'" + enkf_update + "'", "perturbed or square_root");
  }
  c.enkf.square_root = enkf_update == "square_root";
  k.finish();
  YamlMapReader g = f.map("grid");
  g.integer("coarse_points", c.grid.coarse_points, CoarseGrid::kMinPoints, 100001);
  g.integer("fine_points", c.grid.fine_points, 5, 100001);
  g.number("fine_span_sigmas", c.grid.fine_span_sigmas, 0.0, kInf, true);
  g.number("border_mass_tolerance", c.grid.border_mass_tolerance, 0.0, 1.0, true);
  g.integer("threads", c.grid.threads, 1, 256);
  g.finish();
  readSafeguards(f, c);
  f.finish();

  YamlMapReader h = root.map("health");
  h.integer("nis_window", c.health.nis_window, 1, 1000000);
  h.number("nis_confidence", c.health.nis_confidence, 0.0, 1.0, true);
  h.integer("coherence_decimation", c.health.coherence_decimation, 2, 1000000);
  h.number("coherence_threshold", c.health.coherence_threshold, 0.0, kInf, true);
  h.number("innovation_gate", c.health.innovation_gate, 0.0, 0.5);
  c.health.predictive_check = readFlag(h, "predictive_check", c.health.predictive_check);
  h.number("rate_window", c.health.rate_window, 0.0, kInf, true);
  h.number("reopen_interval", c.health.reopen_interval, 0.0, kInf, true);
  h.finish();

  YamlMapReader d = root.map("pdf");
  d.integer("draws", c.pdf.draws, 100, 100000000);
  d.integer("bins", c.pdf.bins, 2, 100000);
  d.unsignedInteger("seed", c.pdf.seed);
  c.pdf.shared_draws = readFlag(d, "shared_draws", c.pdf.shared_draws);
  d.finish();
}

bool readFlag(YamlMapReader& r, const std::string& key, bool value) {
  std::string text = value ? "true" : "false";
  r.text(key, text);
  if (text == "true" || text == "True" || text == "TRUE") return true;
  if (text == "false" || text == "False" || text == "FALSE") return false;
  r.fail(key, "'" + text + "'", "true or false");
}

void readNode(YamlMapReader r, NodeConfig& n, const ModelType& type) {
  // One JointState name per suspension of the model, under its key.
  YamlMapReader j = r.map("joints");
  const auto& suspensions = type.suspensions();
  n.joint_names.clear();
  for (const auto& s : suspensions) {
    std::string name = s.default_joint;
    j.text(s.config_key, name);
    if (name.empty()) j.fail(s.config_key, "(empty)", "a joint name");
    for (std::size_t k = 0; k < n.joint_names.size(); ++k) {
      if (n.joint_names[k] == name) {
        j.fail(s.config_key, "'" + name + "'",
               "a name different from joints." + suspensions[k].config_key);
      }
    }
    n.joint_names.push_back(name);
  }
  j.finish();
  n.reset_on_time_jump = readFlag(r, "reset_on_time_jump", n.reset_on_time_jump);
  r.number("time_jump_tolerance", n.time_jump_tolerance, 0.0, 1e6);
  n.publish_pdf = readFlag(r, "publish_pdf", n.publish_pdf);
  r.integer("pdf_every", n.pdf_every, 1, 1000000000);
  r.integer("derived_every", n.derived_every, 1, 1000000000);
  r.number("road_wait_timeout", n.road_wait_timeout, 0.0, 3600.0);
  r.integer("max_pending_samples", n.max_pending_samples, 1, 100000000);
  r.number("imu_max_gap", n.imu_max_gap, 1e-6, 3600.0);
  r.integer("max_batch_samples", n.max_batch_samples, 1, 100000000);
  r.integer("max_road_samples", n.max_road_samples, 2, 1000000000);
  r.integer("queue_size", n.queue_size, 1, 100000000);
  n.coherence_check = readFlag(r, "coherence_check", n.coherence_check);
  std::string batch = toString(n.batch_method);
  r.text("batch_method", batch);
  if (batch == "es_mda")
    n.batch_method = BatchMethod::kEsMda;
  else if (batch == "whole_set")
    n.batch_method = BatchMethod::kWholeSet;
  else
    r.fail("batch_method", "'" + batch + "'", "es_mda or whole_set");
  r.finish();
}

// `key`[i], or `key`.name with `by_name` (values given physically).
void checkGermPoint(const YamlMapReader& r, const std::string& key, const EstimatorConfig& c,
                    const std::vector<double>& xi, bool by_name = false) {
  for (std::size_t i = 0; i < xi.size(); ++i) {
    const GermFamily f = c.uncertain[i].germ.family;
    const bool bounded = f == GermFamily::kBeta || f == GermFamily::kUniform;
    if (!std::isfinite(xi[i]) || (bounded && std::abs(xi[i]) > 1.0) ||
        (f == GermFamily::kGamma && xi[i] < 0)) {
      r.fail(by_name ? key + "." + c.uncertain[i].name : key + "[" + std::to_string(i) + "]",
             (by_name ? "at xi = " : "") + std::to_string(xi[i]),
             "a point in the support of germ " + describe(c.uncertain[i].germ));
    }
  }
}

// One change of truth.schedule: `xi` (all germs) or `values` (physical values
// of some uncertain parameters, the others as before).
TruthChange readChange(YamlMapReader e, const EstimatorConfig& c, double previous_time,
                       const std::vector<double>& previous_xi) {
  TruthChange ch;
  if (!e.has("time")) e.fail("time", "(empty)", "a time in s");
  e.number("time", ch.time, 0.0, kInf, true);
  if (ch.time <= previous_time) {
    e.fail("time", std::to_string(ch.time),
           "a time after the previous change's " + std::to_string(previous_time) +
               " (times increasing)");
  }
  const std::size_t n = c.uncertain.size(), loads = c.loadCount();
  if (e.has("xi") == e.has("values")) {
    e.fail("xi", e.has("xi") ? "given with values" : "(empty)", "either xi or values");
  }
  ch.xi = previous_xi;  // tolerances keep their truth
  std::vector<double> xi(previous_xi.begin(), previous_xi.begin() + loads);
  e.numberList("xi", xi, loads, loads);
  std::copy(xi.begin(), xi.end(), ch.xi.begin());
  YamlMapReader v = e.map("values");
  for (std::size_t i = 0; i < loads; ++i) {
    const UncertainParameter& u = c.uncertain[i];
    if (!v.has(u.name)) continue;
    double value = 0.0;
    v.number(u.name, value, -kInf, kInf);
    ch.xi[i] = (value / u.nominal - 1.0) / u.relative_range;
  }
  v.finish();
  checkGermPoint(e, e.has("xi") ? "xi" : "values", c,
                 std::vector<double>(ch.xi.begin(), ch.xi.begin() + loads), !e.has("xi"));
  (void)n;
  e.finish();
  return ch;
}

// Values given per selected channel (in `selected`'s order), in the model's
// channel order; the channels not selected take `fill`.
std::vector<double> inModelOrder(const std::vector<double>& given,
                                 const std::vector<std::string>& selected,
                                 const std::vector<std::string>& model_channels, double fill) {
  std::vector<double> out(model_channels.size(), fill);
  for (std::size_t i = 0; i < selected.size(); ++i) {
    const auto it = std::find(model_channels.begin(), model_channels.end(), selected[i]);
    out[static_cast<std::size_t>(it - model_channels.begin())] = given[i];
  }
  return out;
}

// The same, the channels not selected at the largest given (unused).
std::vector<double> inModelOrder(const std::vector<double>& given,
                                 const std::vector<std::string>& selected,
                                 const std::vector<std::string>& model_channels) {
  return inModelOrder(given, selected, model_channels,
                      *std::max_element(given.begin(), given.end()));
}

// measurement.<key>: one number >= 0 for every channel, or a list with one
// per channel of measurement.channels (its order) or of the model.
void readPerChannel(YamlMapReader& m, const std::string& key, const MeasurementConfig& mc,
                    double& scalar, std::vector<double>& per_channel,
                    const std::vector<std::string>& model_channels) {
  if (!m.isSequence(key)) {
    m.number(key, scalar, 0.0, std::numeric_limits<double>::infinity());
    return;
  }
  std::vector<double> list;
  m.numberList(key, list, 1, std::max(mc.channels.size(), model_channels.size()));
  for (std::size_t i = 0; i < list.size(); ++i) {
    if (!(list[i] >= 0.0)) {
      m.fail(key + "[" + std::to_string(i) + "]", roundTripText(list[i]), "a number >= 0");
    }
  }
  if (list.size() == mc.channels.size()) {
    per_channel = inModelOrder(list, mc.channels, model_channels);
  } else if (list.size() == model_channels.size()) {
    per_channel = list;
  } else {
    m.fail(key, "a list of " + std::to_string(list.size()),
           "one number, or one per channel of measurement.channels (" +
               std::to_string(mc.channels.size()) + ") or of the model (" +
               std::to_string(model_channels.size()) + ")");
  }
}

void readTruth(YamlMapReader t, EstimatorConfig& c) {
  if (t.has("road")) {
    YamlMapReader road = t.map("road");
    RoadConfig truth_road = readRoad(road);
    if (truth_road.source == RoadSource::kNone || truth_road.source == RoadSource::kTopic) {
      t.fail("road", "source " + toString(truth_road.source),
             "a road to simulate (speed_bump, sine, series, course, iso8608 or profile)");
    }
    c.truth.road = std::make_shared<const RoadConfig>(std::move(truth_road));
  }
  const int n = static_cast<int>(c.uncertain.size()), loads = c.loadCount();
  // truth.xi: one per `uncertain:` entry (the tolerances' truth is the truth
  // vehicle's value), or one per estimated parameter.
  c.truth.xi.assign(loads, 0.0);
  t.numberList("xi", c.truth.xi, loads, n);
  checkGermPoint(t, "xi", c, std::vector<double>(c.truth.xi.begin(), c.truth.xi.begin() + loads));
  const bool xi_for_tolerances = static_cast<int>(c.truth.xi.size()) == n && n != loads;
  if (n != loads && !xi_for_tolerances && static_cast<int>(c.truth.xi.size()) != loads) {
    t.fail("xi", "a list of " + std::to_string(c.truth.xi.size()),
           std::to_string(loads) + " or " + std::to_string(n) + " germ coordinates");
  }
  t.unsignedInteger("seed", c.truth.seed);

  YamlMapReader v = t.map("vehicle");
  const bool override_vehicle = !v.empty();
  for (int i = 0; i < loads; ++i) {
    const UncertainParameter& u = c.uncertain[i];
    if (v.has(u.name)) {
      throw ConfigError(c.source + ": key '" + v.keyPath(u.name) + "': " + u.name +
                        " is uncertain; its truth comes from truth.xi (and truth.schedule), "
                        "not truth.vehicle");
    }
  }
  if (override_vehicle) {
    c.truth.model = readVehicleSection(v, c.model_type->description(), *c.model);
    v.finish();
  }
  // A tolerance's truth: the truth vehicle's value, as a germ coordinate that
  // may lie outside the tolerance (a vehicle the tolerance does not cover).
  if (!xi_for_tolerances) {
    const std::shared_ptr<const ModelParameters> truth = c.truthModelParameters();
    const Eigen::VectorXd& truth_values = truth->values;
    const auto& names = c.model_type->parameterNames();
    for (int i = loads; i < n; ++i) {
      const UncertainParameter& u = c.uncertain[i];
      const auto at = std::find(names.begin(), names.end(), u.name) - names.begin();
      c.truth.xi.push_back((truth_values[at] / u.nominal - 1.0) / u.relative_range);
    }
  }

  // One number for all, or one per channel of measurement.channels or of the model.
  const std::vector<std::string>& model_channels = c.model_type->channelNames();
  const std::size_t kChannels = model_channels.size(), selected = c.measurement.channels.size();
  YamlMapReader s = t.map("sensor");
  const auto perChannel = [&](const char* key, std::vector<double>& v, double min) {
    const std::size_t given = s.isSequence(key) ? s.sequence(key).size() : 0;
    if (given > 0 && given != selected && given != kChannels) {
      s.fail(key, "a list of " + std::to_string(given),
             "a list of " + std::to_string(selected) + " numbers (one per channel of "
             "measurement.channels) or " + std::to_string(kChannels) +
             " (one per channel of the model), or one number");
    }
    const bool per_selected = given == selected && selected != kChannels;
    s.numberPerItem(key, v, per_selected ? selected : kChannels, min, kInf);
    if (per_selected && !v.empty()) {
      v = inModelOrder(v, c.measurement.channels, model_channels, 0.0);
    }
  };
  perChannel("noise_floor", c.truth.sensor.noise_floor, 0.0);
  perChannel("bias", c.truth.sensor.bias, -kInf);
  perChannel("quantisation", c.truth.sensor.quantisation, 0.0);
  s.finish();

  YamlMapReader g = t.map("timing");
  g.number("jitter", c.truth.timing.jitter, 0.0, kInf);
  g.number("stamp_error", c.truth.timing.stamp_error, 0.0, kInf);
  g.number("drop_fraction", c.truth.timing.drop_fraction, 0.0, 1.0);
  if (c.truth.timing.drop_fraction >= 1.0) {
    g.fail("drop_fraction", "1", "a probability in [0, 1)");
  }
  g.unsignedInteger("seed", c.truth.timing.seed);
  g.number("imu_clock_offset", c.truth.timing.imu_clock_offset, -1.0, 1.0);
  g.finish();

  YamlMapReader x = t.map("cross_fall");
  x.number("start", c.truth.cross_fall.start, -0.5, 0.5);
  c.truth.cross_fall.end = c.truth.cross_fall.start;  // unless given: constant
  x.number("end", c.truth.cross_fall.end, -0.5, 0.5);
  x.number("at", c.truth.cross_fall.at, 0.0, kInf);
  x.number("over", c.truth.cross_fall.over, 0.0, kInf);
  x.finish();

  std::string load_change = "jump";
  t.text("load_change", load_change);
  if (load_change != "jump" && load_change != "settle") {
    t.fail("load_change", "'" + load_change + "'", "jump or settle");
  }
  c.truth.settle_changes = load_change == "settle";
  const YAML::Node seq = t.sequence("schedule");
  for (std::size_t i = 0; seq.IsDefined() && !seq.IsNull() && i < seq.size(); ++i) {
    const bool first = c.truth.schedule.empty();
    c.truth.schedule.push_back(
        readChange(YamlMapReader(seq[i], t.keyPath("schedule[" + std::to_string(i) + "]"),
                                 t.source()),
                   c, first ? 0.0 : c.truth.schedule.back().time,
                   first ? c.truth.xi : c.truth.schedule.back().xi));
  }
  t.finish();
}

}  // namespace

std::string toString(BatchMethod m) { return m == BatchMethod::kWholeSet ? "whole_set" : "es_mda"; }

std::string toString(RoadSource s) {
  switch (s) {
    case RoadSource::kSpeedBump: return "speed_bump";
    case RoadSource::kSine: return "sine";
    case RoadSource::kSeries: return "series";
    case RoadSource::kTopic: return "topic";
    case RoadSource::kCourse: return "course";
    case RoadSource::kIso8608: return "iso8608";
    case RoadSource::kProfile: return "profile";
    case RoadSource::kNone: return "none";
  }
  return "?";
}

std::vector<std::string> defaultJointNames(const ModelType& type) {
  std::vector<std::string> names;
  for (const auto& s : type.suspensions()) names.push_back(s.default_joint);
  return names;
}

std::shared_ptr<const ModelParameters> EstimatorConfig::modelParameters() const {
  return model ? model : model_type->defaults();
}

std::shared_ptr<const ModelParameters> EstimatorConfig::truthModelParameters() const {
  return truth.model ? truth.model : modelParameters();
}

std::vector<GermSpec> EstimatorConfig::germs() const {
  std::vector<GermSpec> g;
  for (const auto& u : uncertain) g.push_back(u.germ);
  return g;
}

Eigen::VectorXd EstimatorConfig::parameterValues(const Eigen::VectorXd& xi) const {
  Eigen::VectorXd v(uncertain.size());
  for (std::size_t i = 0; i < uncertain.size(); ++i) {
    v[i] = uncertain[i].nominal * (1.0 + uncertain[i].relative_range * xi[i]);
  }
  return v;
}

namespace {

}  // namespace

ReadingSettings MeasurementConfig::readings(const ModelDescription& model) const {
  ReadingSettings r;
  r.zero = zero;
  r.as_states = zero == ZeroConvention::kTare;
  for (const ChannelSpec& spec : model.channels()) {
    if (spec.selected_by_default) continue;
    r.as_states |= std::find(channels.begin(), channels.end(), spec.name) != channels.end();
  }
  return r;
}

EstimatorConfig parseConfig(const YAML::Node& given, const std::string& source_name,
                            const ModelRegistry& models) {
  EstimatorConfig c;
  c.source = source_name;
  const YAML::Node node = mergeVehicleFile(given, source_name, &c.vehicle_file);
  YamlMapReader root(node, "", source_name);
  YamlMapReader model = root.map("model");
  std::string type = c.model_type->name();
  model.text("type", type);
  try {
    c.model_type = models.find(type);
  } catch (const std::exception& e) {
    model.fail("type", "'" + type + "'", std::string("a loadable model (") + e.what() + ")");
  }
  if (!c.model_type) {
    std::string known;
    for (const auto& name : models.builtinNames()) known += (known.empty() ? "" : ", ") + name;
    model.fail("type", "'" + type + "'", known + " or a plugin's package/Class");
  }
  model.finish();
  {
    YamlMapReader v = root.map("vehicle");
    c.model = readVehicleSection(v, c.model_type->description(), *c.model_type->defaults());
    v.finish();
  }
  c.uncertain = readUncertain(root, *c.model_type, *c.model);
  const std::vector<UncertainParameter> tolerances =
      readTolerances(root, *c.model_type, *c.model, c.uncertain);
  c.uncertain.insert(c.uncertain.end(), tolerances.begin(), tolerances.end());
  c.tolerance_count = static_cast<int>(tolerances.size());
  if (c.uncertain.empty()) {
    root.fail("tolerances", "(no positive tolerance)",
              "at least one uncertain parameter or a positive tolerance");
  }
  root.number("tolerances_prune", c.tolerances_prune, 0.0, 1.0);
  const int n = static_cast<int>(c.uncertain.size());

  YamlMapReader pc = root.map("pc");
  pc.integer("order", c.pc_order, 0, 20);
  c.pc_truncation = readTruncation(pc);
  const bool interactions = readFlag(pc, "tolerance_interactions", true);
  if (!interactions) c.pc_truncation.single_from = c.loadCount();
  const bool batch_given = pc.has("batch_tolerance_interactions");
  const bool batch_interactions = readFlag(pc, "batch_tolerance_interactions", interactions);
  if (batch_given) c.batch_tolerance_interactions = batch_interactions;
  pc.finish();
  const std::size_t terms = basisSize(n, c.pc_order, c.pc_truncation);
  const std::size_t batch_terms = basisSize(n, c.pc_order, c.batchTruncation());

  YamlMapReader col = root.map("collocation");
  // auto (the default): when the config sets no point count nor a Halton
  // setting (points, batch_points, start_index, seed), the tensor Gauss rule
  // with pc.order + 1 nodes per germ if it has no more nodes than the default
  // Q (autoGaussNodes; both designs then use them); otherwise plain Halton up
  // to kPlainHaltonMaxDimension germs, scrambled Halton above
  // (collocation_design.h), and a given `points` is that design's Q.
  std::string seq = "auto";
  col.text("sequence", seq);
  try {
    if (seq == "auto") {
      const bool halton_keys = col.has("points") || col.has("batch_points") ||
                               col.has("start_index") || col.has("seed");
      const int gauss_nodes =
          halton_keys ? 0 : autoGaussNodes(n, c.pc_order, c.collocation.points);
      if (gauss_nodes > 0) {
        c.collocation.sequence = PointSequence::kGauss;
        c.collocation.points = gauss_nodes;
      } else {
        c.collocation.sequence = defaultPointSequence(n);
      }
    } else {
      c.collocation.sequence = pointSequenceFromString(seq);
    }
  } catch (const std::invalid_argument&) {
    col.fail("sequence", "'" + seq + "'",
             "auto, halton, scrambled_halton, hammersley, gauss or smolyak");
  }
  if (seq == "auto") seq = toString(c.collocation.sequence);
  col.integer("points", c.collocation.points, 1, 1000000);
  const bool batch_points_given = col.has("batch_points");
  int batch_points = c.collocation.points;
  col.integer("batch_points", batch_points, 1, 1000000);
  if (batch_points_given) c.collocation.batch_points = batch_points;
  col.integer("level", c.collocation.level, 0, 30);
  std::string projection = toString(c.collocation.projection);
  col.text("projection", projection);
  try {
    c.collocation.projection = projectionMethodFromString(projection);
  } catch (const std::invalid_argument&) {
    col.fail("projection", "'" + projection + "'", "auto, regression or quadrature");
  }
  // The design's rules (designRuleBreach), for both designs: the one-step
  // filter's and the batch methods' (collocation.batch_points).
  const auto checkDesign = [&](int count, std::size_t basis_terms, const char* points_key) {
    const SettingBreach b =
        designRuleBreach(c.collocation.sequence, count, c.collocation.projection, n, c.pc_order,
                         basis_terms);
    if (b.broken()) col.fail(b.setting == "points" ? points_key : b.setting, b.value, b.needs);
  };
  checkDesign(c.collocation.designCount(c.pc_order), terms, "points");
  checkDesign(c.collocation.sequence == PointSequence::kSmolyak
                  ? c.collocation.designCount(c.pc_order)
                  : c.collocation.batchPoints(),
              batch_terms, "batch_points");
  c.collocation.nested = readFlag(col, "nested", c.collocation.nested);
  if (c.collocation.nested && c.collocation.sequence != PointSequence::kSmolyak) {
    col.fail("nested", "true", "false for sequence " + seq + " (nested rules are smolyak's)");
  }
  col.unsignedInteger("start_index", c.collocation.start_index);
  col.unsignedInteger("seed", c.collocation.seed);
  col.number("max_condition", c.collocation.max_condition, 1.0, kInf);
  col.integer("threads", c.collocation.threads, 0, 1024);
  col.number("loo_warning", c.collocation.loo_warning, 0.0, kInf);
  const double q = c.collocation.sequence == PointSequence::kGauss
                       ? std::pow(c.collocation.points, n)
                       : c.collocation.points;
  constexpr double kMaxTensorNodes = 20000;  // ~ a second of model runs per sample
  if (c.collocation.sequence == PointSequence::kGauss && q > kMaxTensorNodes) {
    col.fail("sequence", "gauss",
             "halton or smolyak for " + std::to_string(n) + " uncertain parameters: the tensor " +
                 "Gauss rule has points^n = " + std::to_string(c.collocation.points) + "^" +
                 std::to_string(n) + " = " + roundTripText(q) +
                 " nodes (more than " + std::to_string(static_cast<int>(kMaxTensorNodes)) +
                 "), a model run each per sample; Halton needs about twice the basis terms (" +
                 std::to_string(terms) + ")");
  }
  const double batch_q = c.collocation.sequence == PointSequence::kGauss
                             ? std::pow(c.collocation.batchPoints(), n)
                             : c.collocation.batchPoints();
  if (c.collocation.sequence == PointSequence::kGauss && batch_q > kMaxTensorNodes) {
    col.fail("batch_points", std::to_string(c.collocation.batchPoints()),
             "at most " + std::to_string(static_cast<int>(kMaxTensorNodes)) +
                 " tensor Gauss nodes (points^n)");
  }
  col.finish();

  c.road = readRoad(root.map("road"));

  YamlMapReader s = root.map("sampling");
  s.integer("samples", c.sampling.samples, 1, 100000000);
  s.number("duration", c.sampling.duration, 0.0, kInf, true);
  s.finish();

  YamlMapReader m = root.map("measurement");
  const std::vector<std::string>& model_channels = c.model_type->channelNames();
  c.measurement.channels = c.model_type->description().defaultChannelNames();
  m.textList("channels", c.measurement.channels);
  const std::set<std::string> known(model_channels.begin(), model_channels.end());
  std::string channel_list;
  for (const auto& ch : model_channels) channel_list += (channel_list.empty() ? "" : ", ") + ch;
  std::set<std::string> seen;
  for (const auto& ch : c.measurement.channels) {
    if (!known.count(ch) || !seen.insert(ch).second) {
      m.fail("channels", "'" + ch + "'", "distinct channels among " + channel_list);
    }
  }
  if (c.measurement.channels.empty()) m.fail("channels", "(empty)", "at least one channel");
  std::string zero = toString(c.measurement.zero);
  m.text("zero", zero);
  if (zero != "rest" && zero != "tare") m.fail("zero", "'" + zero + "'", "rest or tare");
  c.measurement.zero = zeroConventionFromString(zero);
  m.number("travel_blend", c.measurement.travel_blend, 0.0, 10.0);
  m.number("standstill", c.measurement.standstill, 0.0, 60.0);
  readPerChannel(m, "noise_relative", c.measurement, c.measurement.noise_relative,
                 c.measurement.noise_relative_per_channel, model_channels);
  m.number("noise_floor", c.measurement.noise_floor, 0.0, kInf);
  // The filters' R: measurement.r_* and sensor_std, the NoiseModel's fields.
  NoiseModel& noise = c.measurement.noise;
  std::vector<double> r_relative_per_channel;
  readPerChannel(m, "r_relative", c.measurement, noise.r_relative, r_relative_per_channel,
                 model_channels);
  noise.channel_relative = Eigen::Map<const Eigen::VectorXd>(
      r_relative_per_channel.data(), static_cast<Eigen::Index>(r_relative_per_channel.size()));
  m.number("r_floor", noise.r_floor, 0.0, kInf, true);
  std::string r_rule = noise.rule == NoiseRule::kSensor ? "sensor" : "paper";
  m.text("r_rule", r_rule);
  if (r_rule != "paper" && r_rule != "sensor") m.fail("r_rule", "'" + r_rule + "'", "paper or sensor");
  noise.rule = r_rule == "sensor" ? NoiseRule::kSensor : NoiseRule::kPaper;
  std::vector<double> sensor_std;
  m.numberList("sensor_std", sensor_std, 0, known.size());
  if (sensor_std.size() == 1) sensor_std.resize(known.size(), sensor_std[0]);
  // One per selected channel (in measurement.channels' order): the model's
  // order, the channels not selected at the largest given (never used).
  if (sensor_std.size() == c.measurement.channels.size()) {
    sensor_std = inModelOrder(sensor_std, c.measurement.channels, model_channels);
  }
  if (noise.rule == NoiseRule::kSensor) {
    if (sensor_std.size() != known.size()) {
      m.fail("sensor_std", sensor_std.empty() ? "(absent)" : "a list of " + std::to_string(sensor_std.size()),
             "with r_rule sensor: one absolute std per channel of measurement.channels, or per channel " + channel_list + " (or one for all)");
    }
    for (double v : sensor_std) {
      if (!(v > 0.0)) m.fail("sensor_std", std::to_string(v), "positive standard deviations (m, m/s)");
    }
  }
  noise.channel_std = Eigen::Map<const Eigen::VectorXd>(
      sensor_std.data(), static_cast<Eigen::Index>(sensor_std.size()));
  m.finish();

  readTruth(root.map("truth"), c);

  YamlMapReader integ = root.map("integration");
  integ.number("max_step", c.integration.max_step, 0.0, 1.0, true);
  std::string method = toString(c.integration.method);
  integ.text("method", method);
  try {
    c.integration.method = integrationMethodFromString(method);
  } catch (const std::invalid_argument&) {
    integ.fail("method", "'" + method + "'", "rk4 or dp5");
  }
  integ.finish();

  readFilterSections(root, c);
  readNode(root.map("node"), c.node, *c.model_type);
  root.finish();
  return c;
}

EstimatorConfig parseConfigString(const std::string& yaml_text, const std::string& source_name,
                                  const ModelRegistry& models) {
  YAML::Node node;
  try {
    node = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name + ": line " + std::to_string(e.mark.line + 1) +
                      ": not valid YAML (" + e.msg + ")");
  }
  return parseConfig(node, source_name, models);
}

namespace {

// The file's YAML with its vehicle_file: made absolute (relative to the file).
YAML::Node loadConfigYaml(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open the configuration file");
  std::stringstream text;
  text << in.rdbuf();
  YAML::Node node;
  try {
    node = YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    throw ConfigError(path + ": line " + std::to_string(e.mark.line + 1) +
                      ": not valid YAML (" + e.msg + ")");
  }
  anchorVehicleFile(node, path);
  return node;
}

}  // namespace

EstimatorConfig loadConfigFile(const std::string& path, const ModelRegistry& models) {
  return parseConfig(loadConfigYaml(path), path, models);
}

std::uint64_t configFileHash(const std::string& path, const ModelRegistry& models) {
  const YAML::Node node = loadConfigYaml(path);
  parseConfig(node, path, models);
  return fnv1a64(canonicalConfigText(mergeVehicleFile(node, path, nullptr)));
}

}  // namespace pc_ekf
