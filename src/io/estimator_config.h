// The one configuration schema shared by estimator_node and the CLIs
// (YAML, rosparam-friendly: plain maps, lists and scalars only).
// Every key with its type, default, domain and meaning: config_schema.cpp
// (docs/configuration.md); config/speed_bump.yaml lists them all too.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/ensemble_kalman_filter.h"
#include "pc_ekf/filter/health.h"
#include "pc_ekf/filter/kalman_update.h"
#include "pc_ekf/filter/measurement.h"
#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/filter/synthetic_data.h"
#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/filter/update_safeguards.h"
#include "pc_ekf/io/config_error.h"
#include "pc_ekf/model/model_type.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/road_input.h"
#include "pc_ekf/model/road_profile.h"
#include "pc_ekf/pc/basis_truncation.h"
#include "pc_ekf/pc/collocation_design.h"
#include "pc_ekf/pc/germ.h"

namespace YAML {
class Node;
}

namespace pc_ekf {

// kIso8608 and kProfile: roads by distance driven at a speed (road_profile.h);
// kNone: no road is known (road-free estimation, docs/method.md §4.10).
enum class RoadSource { kSpeedBump, kSine, kSeries, kTopic, kCourse, kIso8608, kProfile, kNone };
std::string toString(RoadSource s);

struct RoadConfig {
  RoadSource source = RoadSource::kSpeedBump;
  SpeedBumpSettings speed_bump;
  SineSettings sine;
  std::string series_file;  // road CSV t,y1,y2 (source: series)
  std::vector<CourseSegment> course;  // source: course
  Iso8608Settings iso8608;            // source: iso8608
  std::string profile_file;           // source: profile (CSV s,left,right, m)
  double speed_kmh = 36.0;            // iso8608 and profile: driving speed
};

// Samples at t_k = k * duration / samples, k = 1..samples (docs/method.md §1.6).
struct SamplingConfig {
  int samples = 10;
  double duration = 3.0;
  double interval() const { return duration / samples; }
};

struct MeasurementConfig {
  // model.type's channels selected by default (parsed); IMU channels by name.
  std::vector<std::string> channels = rollPlaneType()->description().defaultChannelNames();
  ZeroConvention zero = ZeroConvention::kRest;  // measurement.zero: rest | tare
  // measurement.travel_blend: road-free, each travel reading blended with its
  // rate's integral over this time constant (s; 0 = the raw readings).
  double travel_blend = 0.0;
  // measurement.standstill: road-free, the window (s) over which a stop is
  // recognised (the inputs then taken as standing: standstill.h); 0 = never.
  double standstill = 0.0;
  double noise_relative = 0.01;  // synthetic data: eps_j ~ N(0, (noise_relative z_true,j)^2)
  double noise_floor = 0.0;      // absolute std added in quadrature (synthetic data)
  // noise_relative as a list in the YAML: one value per channel (the model's
  // order here; empty = noise_relative for every channel).
  std::vector<double> noise_relative_per_channel;
  // The filters' R (NoiseModel), from measurement.r_rule (rule), r_relative
  // (r_relative, or a list: channel_relative), r_floor and sensor_std
  // (channel_std); per channel vectors in the model's channel order.
  NoiseModel noise;
  // The model's readings: the zero convention, and readings kept as states
  // when the convention or a selected channel (IMU) needs them.
  ReadingSettings readings(const ModelDescription& model) const;
};

// From `time` on the truth is at germ point `xi` (synthetic data).
struct TruthChange {
  double time = 0.0;
  std::vector<double> xi;
};

struct TruthConfig {
  std::vector<double> xi;  // germ coordinates of the truth, one per uncertain parameter
  std::uint64_t seed = 1;  // measurement-noise seed
  // The model's values with truth.vehicle applied (unset: the config's `model`).
  std::shared_ptr<const ModelParameters> model;
  SensorImperfections sensor;  // per model channel
  TimingImperfections timing;
  std::vector<TruthChange> schedule;  // times increasing, > 0
  // truth.load_change: settle (true: the body stays put and settles) | jump.
  bool settle_changes = false;
  // The road the truth drives on (truth.road; unset: the config's road). A
  // road-free config (road.source: none) needs it for synthetic drives.
  std::shared_ptr<const RoadConfig> road;
  // truth.cross_fall: the road's cross-fall under the truth (0: level).
  CrossFall cross_fall;
};

struct CollocationConfig {
  PointSequence sequence = PointSequence::kHalton;
  // The parser's default; its `sequence: auto` may take the tensor Gauss rule
  // instead (points = nodes per germ, autoGaussNodes).
  int points = 30;
  int level = -1;  // smolyak only; -1 = the PC order (the lowest exact for the projection)
  ProjectionMethod projection = ProjectionMethod::kAuto;
  bool nested = false;  // smolyak: nested Clenshaw-Curtis rules for symmetric bounded germs
  std::uint64_t start_index = 1;
  std::uint64_t seed = 1;  // scrambled_halton: the scrambling's seed
  double max_condition = 1e8;
  int threads = 0;  // forecast threads; 0 = the machine's cores
  int batch_points = 0;  // collocation.batch_points, the batch methods' Q; 0: points
  int batchPoints() const { return batch_points > 0 ? batch_points : points; }
  // Relative leave-one-out error of the forecast above which a warning is raised.
  double loo_warning = 0.1;
  // The count CollocationDesign takes: points, or the level for smolyak.
  int designCount(int pc_order) const {
    return sequence == PointSequence::kSmolyak ? (level < 0 ? pc_order : level) : points;
  }
};

// The health: section: the checks' limits (HealthLimits), and the keys of
// the node's coherence filter, the one-step gate and the batch methods' check.
struct HealthConfig : HealthLimits {
  int coherence_decimation = 10;
  double coherence_threshold = 3.0;
  double innovation_gate = 0.0;  // one-step: tail probability of the NIS gate (0 = off)
  bool predictive_check = true;  // batch methods: posterior-predictive check drives health
};

struct PdfConfig {
  int draws = 100000;
  int bins = 60;
  std::uint64_t seed = 11;
  // One set of germ draws for every parameter (cost independent of n); false:
  // parameter i draws with seed + i (the paper configs' numbers).
  bool shared_draws = false;
};

// estimator_node only (section `node:`); the CLIs accept and ignore it.
enum class BatchMethod { kEsMda, kWholeSet };

// A model type's default joint names, in suspensions() order.
std::vector<std::string> defaultJointNames(const ModelType& type);
std::string toString(BatchMethod m);

struct NodeConfig {
  // One JointState name per suspension (ModelType::suspensions() order;
  // node.joints.<config_key>); parsed: the model's defaults, then node.joints.
  std::vector<std::string> joint_names = defaultJointNames(*rollPlaneType());
  bool reset_on_time_jump = false;               // else a sample stamped back in time is dropped
  double time_jump_tolerance = 0.5;              // s: a step back beyond this is a time jump
  bool publish_pdf = true;
  int pdf_every = 1;               // publish parameter_pdf every k-th sample
  // The derived quantities (rollover outputs) projected every k-th sample
  // (and at a PDF, load change or re-linearisation); the estimates between
  // carry the latest.
  int derived_every = 10;
  double road_wait_timeout = 0.5;  // s (wall clock) without road data before a sample goes on
  int max_pending_samples = 1000;  // samples waiting for road data (or for the IMU)
  // imu/data (docs/nodes.md "Clocks"): two IMU messages further apart than
  // this do not bracket a suspension sample (the IMU stopped): no IMU channels.
  double imu_max_gap = 0.1;  // s
  int max_batch_samples = 100000;  // kept for ~estimate_batch (the first ones)
  int max_road_samples = 1000000;  // road buffer bound
  int queue_size = 20000;          // subscriber and publisher queues
  bool coherence_check = true;     // second filter on every k-th sample (docs/method.md §5.2)
  BatchMethod batch_method = BatchMethod::kEsMda;
};

struct EstimatorConfig {
  std::string source = "<config>";  // file name, for messages
  // model.type (its description: model_type->description(), whose
  // parameters() table gives names, units, defaults and domains) and the
  // values of its `vehicle:` section (the full parameter vector, settings
  // and choices in the description's order).
  std::shared_ptr<const ModelType> model_type = rollPlaneType();
  std::shared_ptr<const ModelParameters> model = model_type->defaults();
  // `model` (the type's defaults when unset).
  std::shared_ptr<const ModelParameters> modelParameters() const;
  // The truth's (truth.vehicle applied).
  std::shared_ptr<const ModelParameters> truthModelParameters() const;
  // What is estimated: first the `uncertain:` entries (the load), then the
  // last `tolerance_count` entries from `tolerances:` (nuisance parameters:
  // vehicle values known to a tolerance, in the model's parameter order).
  std::vector<UncertainParameter> uncertain;
  int tolerance_count = 0;
  int loadCount() const { return static_cast<int>(uncertain.size()) - tolerance_count; }
  std::string vehicle_file;       // the merged vehicle_file ("" without one)
  double tolerances_prune = 0.0;  // fix tolerances with every total Sobol index below this
  int pc_order = 4;
  BasisTruncation pc_truncation;  // pc.truncation, pc.q_norm, pc.tolerance_interactions
  // pc.batch_tolerance_interactions: -1 (absent) as pc.tolerance_interactions,
  // 0 false, 1 true; the batch methods' basis is batchTruncation().
  int batch_tolerance_interactions = -1;
  BasisTruncation batchTruncation() const {
    BasisTruncation t = pc_truncation;
    if (batch_tolerance_interactions >= 0) {
      t.single_from = batch_tolerance_interactions ? -1 : loadCount();
    }
    return t;
  }
  CollocationConfig collocation;
  RoadConfig road;
  SamplingConfig sampling;
  MeasurementConfig measurement;
  TruthConfig truth;
  IntegratorSettings integration;
  UpdateRule update = UpdateRule::kSquareRoot;
  EsMdaSettings es_mda;
  EnkfEnsemble enkf;
  PosteriorGrid grid;
  HealthConfig health;
  // filter.support, .drift, .reopen, .relinearize; damp unless configured.
  SafeguardSettings safeguards{SupportRule::kDamp,   Eigen::VectorXd(),     Eigen::VectorXd(),
                               ReopenSettings(),     RelinearizeSettings(), MovingHorizonSettings()};
  PdfConfig pdf;
  NodeConfig node;

  std::vector<GermSpec> germs() const;
  // Parameter values at germ point xi (one entry per uncertain parameter).
  Eigen::VectorXd parameterValues(const Eigen::VectorXd& xi) const;
};

// Throws ConfigError. `models` resolves model.type (built-ins by default).
EstimatorConfig loadConfigFile(const std::string& path,
                               const ModelRegistry& models = ModelRegistry::builtins());
EstimatorConfig parseConfig(const YAML::Node& root, const std::string& source_name,
                            const ModelRegistry& models = ModelRegistry::builtins());
// The identity of a config file (config_identity.h) as estimator_node's
// checkpoints hold it: the config merged with its vehicle file's contents.
// The file is checked as loadConfigFile does (throws ConfigError).
std::uint64_t configFileHash(const std::string& path,
                             const ModelRegistry& models = ModelRegistry::builtins());
EstimatorConfig parseConfigString(const std::string& yaml_text, const std::string& source_name,
                                  const ModelRegistry& models = ModelRegistry::builtins());

}  // namespace pc_ekf
