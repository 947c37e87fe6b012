#include "pc_ekf/io/estimation_setup.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "pc_ekf/io/measurement_csv.h"

namespace pc_ekf {

namespace {

std::shared_ptr<const ContactRoad> roadOf(const EstimatorConfig& c, const RoadConfig& road);

}  // namespace

std::shared_ptr<const ContactRoad> makeRoad(const EstimatorConfig& c,
                                            std::shared_ptr<const ContactRoad> sampled) {
  if (sampled) return sampled;
  if (c.road.source == RoadSource::kNone) {
    throw std::invalid_argument(c.source + ": road.source is none: the road-free model is built "
                                "from the record (makeRoadFreeModel)");
  }
  return roadOf(c, c.road);
}

std::shared_ptr<const ContactRoad> makeTruthRoadLevel(const EstimatorConfig& c);

std::shared_ptr<const ContactRoad> makeTruthRoad(const EstimatorConfig& c) {
  std::shared_ptr<const ContactRoad> road = makeTruthRoadLevel(c);
  if (!c.truth.cross_fall.active()) return road;
  // The cross-fall: gravity's share along the tilted vehicle's y axis.
  return std::make_shared<RoadWithMotion>(
      road, std::make_shared<CrossFallMotion>(road, c.truth.cross_fall, 9.81));
}

std::shared_ptr<const ContactRoad> makeTruthRoadLevel(const EstimatorConfig& c) {
  if (c.truth.road) return roadOf(c, *c.truth.road);
  if (c.road.source == RoadSource::kNone) {
    throw ConfigError(c.source + ": key 'truth.road': road.source is none, so a synthetic drive " +
                      "needs the road the truth drives on (e.g. truth: {road: {source: iso8608}}); " +
                      "or give the drive with --measurements or --bag");
  }
  return makeRoad(c);
}

namespace {

std::shared_ptr<const ContactRoad> roadOf(const EstimatorConfig& cfg, const RoadConfig& road) {
  EstimatorConfig c = cfg;
  c.road = road;
  const ModelType& type = *c.model_type;
  const auto needTwo = [&](const char* source) {
    if (type.twoContacts()) return;
    throw ConfigError(c.source + ": key 'road.source': " + source + " is a road under two contacts; " +
                      "model " + type.name() + " has " + std::to_string(type.contactNames().size()) +
                      " (use speed_bump, series or topic)");
  };
  switch (c.road.source) {
    case RoadSource::kSpeedBump: return type.speedBump(c.road.speed_bump, *c.modelParameters());
    case RoadSource::kSine: needTwo("sine"); return std::make_shared<SineRoad>(c.road.sine);
    case RoadSource::kSeries: {
      try {
        const ContactSeries r = readContactRoadCsvFile(c.road.series_file, type.roadColumns());
        return std::make_shared<SampledRoad>(r.t, r.heights);
      } catch (const CsvError& e) {
        throw ConfigError(c.source + ": key 'road.series.file': " + e.what());
      }
    }
    case RoadSource::kCourse: return type.course(c.road.course, *c.modelParameters());
    case RoadSource::kIso8608:
      return type.drivenProfile(std::make_shared<Iso8608Profile>(c.road.iso8608),
                                c.road.speed_kmh / 3.6, *c.modelParameters());
    case RoadSource::kProfile: {
      std::shared_ptr<const MeasuredProfile> profile;
      try {
        profile = readMeasuredProfileCsv(c.road.profile_file);
      } catch (const std::invalid_argument& e) {
        throw ConfigError(c.source + ": key 'road.profile.file': " + e.what());
      }
      return type.drivenProfile(profile, c.road.speed_kmh / 3.6, *c.modelParameters());
    }
    case RoadSource::kTopic: break;
    case RoadSource::kNone: break;
  }
  throw std::invalid_argument(c.source + ": road.source is " + toString(c.road.source) +
                              " but no road samples were given");
}

}  // namespace

std::shared_ptr<const MechanicalModel> makeModel(const EstimatorConfig& c,
                                                 std::shared_ptr<const ContactRoad> road) {
  const ReadingSettings readings = c.measurement.readings(c.model_type->description());
  auto model = c.model_type->build(*c.modelParameters(), std::move(road), readings);
  for (int i : channelIndices(c)) {
    if (!model->channelModelled(i)) {
      throw ConfigError(c.source + ": key 'measurement.channels': model " + c.model_type->name() +
                        " cannot give '" + model->channelNames()[static_cast<std::size_t>(i)] +
                        "' as built");
    }
  }
  return model;
}

void checkToleranceDomain(const EstimatorConfig& c, const MechanicalModel& model,
                          const ParameterMapping& mapping) {
  for (int i = c.loadCount(); i < mapping.count(); ++i) {
    const UncertainParameter& u = mapping.uncertain()[i];
    for (const double end : {mapping.lowerBound(i), mapping.upperBound(i)}) {
      if (!std::isfinite(end)) continue;
      Eigen::VectorXd v = model.nominalParameters();
      v[model.parameterIndex(u.name)] = end;
      const std::string why = model.invalidReason(v);
      if (!why.empty()) {
        throw ConfigError(c.source + ": key 'tolerances." + u.name + "': relative range " +
                          std::to_string(u.relative_range) + " around " +
                          std::to_string(u.nominal) + " reaches " + std::to_string(end) +
                          ", outside the model's domain (" + why + ")");
      }
    }
  }
}

EstimatorConfig batchDesignConfig(EstimatorConfig c) {
  c.pc_truncation = c.batchTruncation();
  c.collocation.points = c.collocation.batchPoints();
  return c;
}

bool separateBatchDesign(const EstimatorConfig& c) {
  return c.batchTruncation().single_from != c.pc_truncation.single_from ||
         c.collocation.batchPoints() != c.collocation.points;
}

std::shared_ptr<const PcPropagator> makePropagator(const EstimatorConfig& c,
                                                   std::shared_ptr<const MechanicalModel> model) {
  ParameterMapping mapping(*model, c.uncertain);
  checkToleranceDomain(c, *model, mapping);
  const PolynomialBasis basis(mapping.germs(), c.pc_order, c.pc_truncation);
  const bool smolyak = c.collocation.sequence == PointSequence::kSmolyak;
  try {
    const CollocationDesign design(basis, c.collocation.sequence,
                                   c.collocation.designCount(c.pc_order), c.collocation.start_index,
                                   c.collocation.max_condition, c.collocation.projection,
                                   c.collocation.nested, c.collocation.seed);
    return std::make_shared<PcPropagator>(std::move(model), basis, design, std::move(mapping),
                                          c.integration, c.collocation.threads);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(c.source + ": key 'collocation." + (smolyak ? "level" : "points") +
                      "': " + e.what());
  }
}

EstimatorConfig withUncertain(EstimatorConfig c, const std::vector<std::string>& names,
                              double range, double xi_truth) {
  const std::shared_ptr<const MechanicalModel> model = makeModel(c, makeRoad(c));
  for (const std::string& name : names) {
    const int index = model->parameterIndex(name);
    if (index < 0)
      throw ConfigError(c.source + ": no model parameter '" + name + "' to declare uncertain");
    UncertainParameter u;
    u.name = name;
    u.nominal = model->nominalParameters()(index);
    u.relative_range = range;
    c.uncertain.push_back(u);
    c.truth.xi.push_back(xi_truth);
  }
  return c;
}

std::shared_ptr<const ParameterPdfSampler> makePdfSampler(const EstimatorConfig& c,
                                                          const PolynomialBasis& basis,
                                                          int parameters, int threads) {
  const PdfSetupThreads t{std::max(1, threads)};
  if (c.pdf.shared_draws) {
    return std::make_shared<const ParameterPdfSampler>(basis, c.pdf.draws, c.pdf.bins, c.pdf.seed, t);
  }
  return std::make_shared<const ParameterPdfSampler>(basis, c.pdf.draws, c.pdf.bins, c.pdf.seed,
                                                     parameters, t);
}

ReferencePosteriorSettings makeReferenceSettings(const EstimatorConfig& c) {
  ReferencePosteriorSettings s;
  static_cast<PosteriorGrid&>(s) = c.grid;
  s.bins = c.pdf.bins;
  return s;
}

OneStepSettings makeOneStepSettings(const EstimatorConfig& c) {
  OneStepSettings s;
  static_cast<SafeguardSettings&>(s) = c.safeguards;
  s.rule = c.update;
  s.noise = c.measurement.noise;
  static_cast<HealthLimits&>(s.health) = c.health;
  s.health.seed = c.pdf.seed;
  s.health.loo_warning = c.collocation.loo_warning;
  s.innovation_gate = c.health.innovation_gate;
  return s;
}

EnkfSettings makeEnkfSettings(const EstimatorConfig& c) {
  return {c.enkf, c.measurement.noise, c.integration, c.grid.threads};
}

std::string zeroConventionProblem(const EstimatorConfig& c, const MeasurementSeries& series) {
  ZeroConventionSum zero(c);
  for (const Measurement& m : series) zero.add(m);
  return zero.problem();
}

ZeroConventionSum::ZeroConventionSum(const EstimatorConfig& c)
    : c_(c), channel_(c.model_type->description().channelIndex("accel_z")) {}

void ZeroConventionSum::add(const Measurement& m) {
  if (channel_ < 0) return;
  for (std::size_t i = 0; i < m.channels.size(); ++i) {
    if (m.channels[i] != channel_) continue;
    sum_ += m.values[static_cast<Eigen::Index>(i)];
    ++count_;
  }
}

std::string ZeroConventionSum::problem() const {
  const EstimatorConfig& c = c_;
  if (channel_ < 0 || count_ == 0) return "";
  const double sum = sum_;
  const long count = count_;
  const int g_index = c.model_type->description().parameters().index("gravity");
  const double g = g_index >= 0 ? c.modelParameters()->values[g_index] : 9.81;
  const double mean = sum / static_cast<double>(count);
  const bool tare = c.measurement.zero == ZeroConvention::kTare;
  const double expected = tare ? g : 0.0;
  if (std::abs(mean - expected) <= 0.5 * g) return "";
  std::ostringstream o;
  o << "accel_z averages " << mean << " m/s^2 over " << count << " readings, but measurement.zero: "
    << (tare ? "tare expects a raw IMU (about +" : "rest expects deviations from rest (about ")
    << expected << " m/s^2): "
    << (tare ? (mean < -0.5 * g ? "the IMU's z axis points down (REP 103: z up)"
                                : "gravity taken out? set measurement.zero: rest")
             : (mean > 0.0 ? "gravity left in? set measurement.zero: tare for a raw IMU"
                           : "the IMU's z axis points down (REP 103: z up)"));
  return o.str();
}

std::vector<int> channelIndices(const EstimatorConfig& c) {
  const std::vector<std::string>& names = c.model_type->channelNames();
  std::vector<int> idx;
  for (std::size_t i = 0; i < names.size(); ++i) {
    for (const auto& ch : c.measurement.channels) {
      if (ch == names[i]) idx.push_back(static_cast<int>(i));
    }
  }
  return idx;
}

// The model the truth is simulated with on `road` (the estimator model's road
// when none is given).
std::shared_ptr<const MechanicalModel> truthOnItsRoad(const EstimatorConfig& c) {
  return c.model_type->build(*c.truthModelParameters(), makeTruthRoad(c),
                             c.measurement.readings(c.model_type->description()));
}

std::shared_ptr<const MechanicalModel> truthModel(const EstimatorConfig& c,
                                                  const MechanicalModel& model) {
  const ReadingSettings readings = c.measurement.readings(c.model_type->description());
  // A road of its own (truth.road), or none in the estimator's model
  // (road-free): the full model on the truth's road.
  if (c.truth.road || c.road.source == RoadSource::kNone) return truthOnItsRoad(c);
  // Non-owning: the estimator's model is the caller's.
  if (!c.truth.model) {
    return std::shared_ptr<const MechanicalModel>(std::shared_ptr<void>(), &model);
  }
  const ContactRoad* road = model.contactRoad();
  if (!road) throw ConfigError(c.source + ": key 'truth.vehicle': the model has no road to share");
  const std::shared_ptr<const ContactRoad> shared(std::shared_ptr<void>(), road);
  return c.model_type->build(*c.truthModelParameters(), shared, readings);
}

namespace {

Eigen::VectorXd fullAt(const EstimatorConfig& c, const MechanicalModel& truth,
                       const std::vector<double>& xi_list) {
  const ParameterMapping mapping(truth, c.uncertain);
  const Eigen::VectorXd xi = Eigen::Map<const Eigen::VectorXd>(xi_list.data(), xi_list.size());
  return mapping.fullParameters(c.parameterValues(xi));
}

}  // namespace

Eigen::VectorXd truthParameters(const EstimatorConfig& c, const MechanicalModel& model) {
  return fullAt(c, *truthModel(c, model), c.truth.xi);
}

Eigen::VectorXd truthXiAt(const EstimatorConfig& c, double t) {
  const std::vector<double>* xi = &c.truth.xi;
  for (const auto& ch : c.truth.schedule) {
    if (ch.time <= t) xi = &ch.xi;
  }
  return Eigen::Map<const Eigen::VectorXd>(xi->data(), xi->size());
}

std::vector<double> syntheticSampleTimes(const EstimatorConfig& c) {
  const std::vector<double> nominal = uniformSampleTimes(c.sampling.samples, c.sampling.duration);
  const SampleTiming timing = drawSampleTiming(nominal, c.truth.timing);
  std::vector<double> out;
  for (std::size_t k = 0; k < nominal.size(); ++k) {
    if (timing.kept[k]) out.push_back(timing.stamps[k]);
  }
  return out;
}

SyntheticDataSettings syntheticSettings(const EstimatorConfig& c, const MechanicalModel& truth,
                                        std::uint64_t seed) {
  SyntheticDataSettings s;
  s.times = uniformSampleTimes(c.sampling.samples, c.sampling.duration);
  s.channels = channelIndices(c);
  s.noise_relative = c.measurement.noise_relative;
  s.channel_noise_relative = c.measurement.noise_relative_per_channel;
  s.noise_floor = c.measurement.noise_floor;
  s.seed = seed;
  s.integration = c.integration;
  s.sensor = c.truth.sensor;
  s.timing = c.truth.timing;
  s.cross_fall = c.truth.cross_fall;
  for (const auto& ch : c.truth.schedule) {
    s.schedule.push_back({ch.time, fullAt(c, truth, ch.xi), c.truth.settle_changes});
  }
  return s;
}

MeasurementSeries synthesizeFromConfig(const EstimatorConfig& c, const MechanicalModel& model,
                                       std::uint64_t seed) {
  const auto truth = truthModel(c, model);
  return synthesizeMeasurements(*truth, fullAt(c, *truth, c.truth.xi),
                                syntheticSettings(c, *truth, seed));
}

ContactSeries sampleContactRoad(const ContactRoad& road, double t_end, double rate) {
  const long count = static_cast<long>(std::ceil(t_end * rate - 1e-9)) + 1;
  ContactSeries r;
  r.t.reserve(count);
  r.heights.assign(road.contactCount(), {});
  Eigen::VectorXd y(road.contactCount());
  for (long i = 0; i < count; ++i) {
    const double t = static_cast<double>(i) / rate;
    road.heights(t, y);
    r.t.push_back(t);
    for (int c = 0; c < road.contactCount(); ++c) r.heights[c].push_back(y(c));
  }
  return r;
}

}  // namespace pc_ekf
