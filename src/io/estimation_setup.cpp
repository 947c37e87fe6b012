#include "io/estimation_setup.h"

#include <cmath>

#include "io/measurement_csv.h"

namespace pc_ekf {

std::shared_ptr<const RoadInput> makeRoad(const EstimatorConfig& c,
                                          std::shared_ptr<const RoadInput> sampled) {
  if (sampled) return sampled;
  switch (c.road.source) {
    case RoadSource::kSpeedBump: return std::make_shared<SpeedBumpRoad>(c.road.speed_bump);
    case RoadSource::kSine: return std::make_shared<SineRoad>(c.road.sine);
    case RoadSource::kSeries: {
      try {
        const RoadSeries r = readRoadCsvFile(c.road.series_file);
        return std::make_shared<SampledRoad>(r.t, r.left, r.right);
      } catch (const CsvError& e) {
        throw ConfigError(c.source + ": key 'road.series.file': " + e.what());
      }
    }
    case RoadSource::kTopic: break;
  }
  throw std::invalid_argument(c.source + ": road.source is topic but no road samples were given");
}

std::shared_ptr<const RollPlaneModel> makeModel(const EstimatorConfig& c,
                                                std::shared_ptr<const RoadInput> road) {
  return std::make_shared<RollPlaneModel>(c.vehicle, std::move(road));
}

std::shared_ptr<const PcPropagator> makePropagator(const EstimatorConfig& c,
                                                   std::shared_ptr<const MechanicalModel> model) {
  ParameterMapping mapping(*model, c.uncertain);
  const PolynomialBasis basis(mapping.germs(), c.pc_order);
  try {
    const CollocationDesign design(basis, c.collocation.sequence, c.collocation.points,
                                   c.collocation.start_index, c.collocation.max_condition);
    return std::make_shared<PcPropagator>(std::move(model), basis, design, std::move(mapping),
                                          c.integration);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(c.source + ": key 'collocation.points': " + e.what());
  }
}

NoiseModel makeNoiseModel(const EstimatorConfig& c) {
  NoiseModel n;
  n.rule = c.measurement.r_rule;
  n.r_relative = c.measurement.r_relative;
  n.r_floor = c.measurement.r_floor;
  n.channel_std = Eigen::Map<const Eigen::VectorXd>(c.measurement.sensor_std.data(),
                                                    c.measurement.sensor_std.size());
  return n;
}

ReferencePosteriorSettings makeReferenceSettings(const EstimatorConfig& c) {
  ReferencePosteriorSettings s;
  s.coarse_points = c.grid.coarse_points;
  s.fine_points = c.grid.fine_points;
  s.fine_span_sigmas = c.grid.fine_span_sigmas;
  s.border_mass_tolerance = c.grid.border_mass_tolerance;
  s.threads = c.grid.threads;
  s.bins = c.pdf.bins;
  return s;
}

OneStepSettings makeOneStepSettings(const EstimatorConfig& c) {
  OneStepSettings s;
  s.rule = c.update;
  s.noise = makeNoiseModel(c);
  s.health.nis_window = c.health.nis_window;
  s.health.nis_confidence = c.health.nis_confidence;
  s.health.seed = c.pdf.seed;
  s.innovation_gate = c.health.innovation_gate;
  s.support = c.safeguards.support;
  s.drift = Eigen::Map<const Eigen::VectorXd>(c.safeguards.drift.data(), c.safeguards.drift.size());
  s.reopen = c.safeguards.reopen;
  return s;
}

EnkfSettings makeEnkfSettings(const EstimatorConfig& c) {
  EnkfSettings s;
  s.members = c.enkf.members;
  s.seed = c.enkf.seed;
  s.noise = makeNoiseModel(c);
  s.integration = c.integration;
  s.threads = c.grid.threads;
  s.square_root = c.enkf.square_root;
  return s;
}

std::vector<int> channelIndices(const EstimatorConfig& c) {
  const std::vector<std::string> names{"u1", "u2", "v1", "v2"};
  std::vector<int> idx;
  for (int i = 0; i < 4; ++i) {
    for (const auto& ch : c.measurement.channels) {
      if (ch == names[i]) idx.push_back(i);
    }
  }
  return idx;
}

Eigen::VectorXd truthParameters(const EstimatorConfig& c, const MechanicalModel& model) {
  const ParameterMapping mapping(model, c.uncertain);
  const Eigen::VectorXd xi = Eigen::Map<const Eigen::VectorXd>(c.truth.xi.data(), c.truth.xi.size());
  return mapping.fullParameters(c.parameterValues(xi));
}

MeasurementSeries synthesizeFromConfig(const EstimatorConfig& c, const MechanicalModel& model,
                                       std::uint64_t seed) {
  SyntheticDataSettings s;
  s.times = uniformSampleTimes(c.sampling.samples, c.sampling.duration);
  s.channels = channelIndices(c);
  s.noise_relative = c.measurement.noise_relative;
  s.noise_floor = c.measurement.noise_floor;
  s.seed = seed;
  s.integration = c.integration;
  return synthesizeMeasurements(model, truthParameters(c, model), s);
}

RoadSeries sampleRoad(const RoadInput& road, double t_end, double rate) {
  const long count = static_cast<long>(std::ceil(t_end * rate - 1e-9)) + 1;
  RoadSeries r;
  r.t.reserve(count);
  r.left.reserve(count);
  r.right.reserve(count);
  for (long i = 0; i < count; ++i) {
    const double t = static_cast<double>(i) / rate;
    const Eigen::Vector2d y = road.height(t);
    r.t.push_back(t);
    r.left.push_back(y(0));
    r.right.push_back(y(1));
  }
  return r;
}

}  // namespace pc_ekf
