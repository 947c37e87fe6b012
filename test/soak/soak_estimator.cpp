// Soak run of estimator_node's per-sample path without the transport: the
// same EstimatorTimeline (road buffer, pending samples) and EstimatorRun
// (one-step + coherence filters, batch buffer, PDFs) the node drives, fed a
// streamed truth simulation and its road at 1 kHz for --samples samples.
// Road-free configs (road.source none): the truth drives truth.road, the
// samples go through the node's RoadFreeStream, whose inputs are forgotten
// behind the filters and the batch as the node does.
// Prints RSS every --report samples; exit 1 when a sample is dropped or RSS
// grows by more than --limit-mb after --warmup samples (soak.sh). --batch 1:
// at the end ~estimate_batch's batch over the kept samples (exit 1 when it
// publishes nothing), which road-free reads from the inputs kept for it.
#include <Eigen/Dense>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <random>
#include <string>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/model/integrator.h"
#include "pc_ekf/pc/pdf_sampler.h"
#include "pc_ekf/ros/estimator_run.h"
#include "pc_ekf/ros/estimator_timeline.h"

namespace {

using namespace pc_ekf;

double rssMb() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return NAN;
}

double seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Options {
  std::string config;
  long samples = 1000000, warmup = 200000, report = 100000;
  double dt = 0.001, limit_mb = 20.0;
  int pdf_every = 1000, max_batch = 100000, max_road = 100000, batch = 0;
};

Options parse(int argc, char** argv) {
  Options o;
  if (argc % 2 == 0) throw std::invalid_argument(std::string("option '") + argv[argc - 1] + "' needs a value");
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--config") o.config = v;
    else if (k == "--samples") o.samples = std::stol(v);
    else if (k == "--warmup") o.warmup = std::stol(v);
    else if (k == "--report") o.report = std::stol(v);
    else if (k == "--dt") o.dt = std::stod(v);
    else if (k == "--limit-mb") o.limit_mb = std::stod(v);
    else if (k == "--pdf-every") o.pdf_every = std::stoi(v);
    else if (k == "--max-batch") o.max_batch = std::stoi(v);
    else if (k == "--max-road") o.max_road = std::stoi(v);
    else if (k == "--batch") o.batch = std::stoi(v);
    else throw std::invalid_argument("unknown option '" + k + "'");
  }
  if (o.config.empty()) throw std::invalid_argument("--config FILE is required");
  if (o.samples < 1 || o.warmup < 0 || o.warmup >= o.samples || o.report < 1 || !(o.dt > 0)) {
    throw std::invalid_argument("need samples > warmup >= 0, report >= 1, dt > 0");
  }
  return o;
}

int run(const Options& o) {
  EstimatorConfig c = loadConfigFile(o.config);
  c.node.max_batch_samples = o.max_batch;
  c.node.max_road_samples = o.max_road;
  c.node.pdf_every = o.pdf_every;

  // The truth: one point of the model on the analytic road (road-free: on
  // truth.road, which the estimator does not know), streamed.
  const bool road_free = c.road.source == RoadSource::kNone;
  const auto analytic_road =
      road_free ? nullptr : std::dynamic_pointer_cast<const RoadInput>(makeRoad(c));
  const auto truth_model = road_free ? truthOnItsRoad(c) : makeModel(c, analytic_road);
  const auto stream =
      road_free ? std::make_unique<RoadFreeStream>(c, RoadFreeStream::inputsFor(c)) : nullptr;
  const auto truth_batch = truth_model->prepare(truthParameters(c, *truth_model));
  Eigen::ArrayXXd y = truth_batch->initialState();
  const std::vector<int> channels = channelIndices(c);
  std::mt19937_64 rng(c.truth.seed);
  std::normal_distribution<double> normal;

  TimelineSettings ts = timelineSettings(c);
  ts.analytic_interval = o.dt;
  EstimatorTimeline timeline(ts);
  const auto prior = makePropagator(
      c, road_free ? stream->model() : makeModel(c, std::make_shared<SampledRoad>(2)));
  const auto pdfs = makePdfSampler(c, prior->basis(), prior->parameterCount());
  std::unique_ptr<EstimatorRun> run;

  const ros::Time origin(1000000, 0);
  long processed = 0, dropped = 0, unhealthy = 0;
  std::string last_warning;  // of the last unhealthy estimate
  double rss_warm = NAN, rss_max_after = 0.0;
  const double start = seconds();
  std::printf("%10s %10s %10s %10s %10s %10s %8s\n", "samples", "rss_mb", "road_buf", "inputs",
              "batch_buf", "unhealthy", "wall_s");
  if (!road_free) {
    const Eigen::Vector2d road0 = analytic_road->height(0.0);
    timeline.addRoad(origin, road0[0], road0[1], seconds());  // t = 0: the origin
  }
  for (long k = 1; k <= o.samples; ++k) {
    const double t = static_cast<double>(k) * o.dt, t_prev = static_cast<double>(k - 1) * o.dt;
    integrate(*truth_model, *truth_batch, t_prev, t, y, c.integration);
    const Eigen::VectorXd z = truth_model->observationMatrix() * y.matrix();
    Measurement m;
    m.channels = channels;
    m.values.resize(static_cast<Eigen::Index>(channels.size()));
    for (std::size_t i = 0; i < channels.size(); ++i) {
      const double v = z[channels[i]];
      const double sd = std::max(c.measurement.noise_floor, c.measurement.noise_relative * std::abs(v));
      m.values[static_cast<Eigen::Index>(i)] = v + sd * normal(rng);
    }
    const ros::Time stamp = origin + ros::Duration(t);
    const double now = seconds();
    if (!road_free) {
      const Eigen::Vector2d road = analytic_road->height(t);
      if (timeline.addRoad(stamp, road[0], road[1], now) != StampVerdict::kAccepted) ++dropped;
    }
    if (timeline.addSample(stamp, m, now) != StampVerdict::kAccepted) ++dropped;
    DroppedSamples lost;
    for (const ReleasedSample& s : timeline.release(now, &lost)) {
      if (!run) {
        run = std::make_unique<EstimatorRun>(
            c, road_free ? prior : makePropagator(c, makeModel(c, timeline.road())), true);
      }
      Measurement outputs;
      if (stream && !stream->add(s.measurement, &outputs).empty()) {
        ++dropped;
        continue;
      }
      const SampleEstimate e = run->process(stream ? outputs : s.measurement, s.stamp);
      // The node draws these on its PDF worker; here inline (same numbers).
      if (e.pdf) parameterPdf(*pdfs, prior->mapping().names(), *e.pdf);
      timeline.keepRoadFrom(run->oldestTime());
      if (stream) stream->forgetInputs(run->oldestTime(), run->batchUntil());
      ++processed;
      unhealthy += !e.estimate.healthy;
      if (!e.estimate.healthy && !e.estimate.warnings.empty()) last_warning = e.estimate.warnings.front();
      dropped += e.non_finite;
    }
    dropped += lost.no_road + lost.before_origin;
    if (k == o.warmup) rss_warm = rssMb();
    if (k > o.warmup) rss_max_after = std::max(rss_max_after, rssMb());
    if (k % o.report == 0 || k == o.samples) {
      std::printf("%10ld %10.1f %10zu %10zu %10zu %10ld %8.1f\n", k, rssMb(),
                  timeline.roadCount(), stream ? stream->inputs().held() : 0,
                  run ? run->batchSamples() : 0, unhealthy, seconds() - start);
      std::fflush(stdout);
    }
  }
  const double growth = rss_max_after - rss_warm;
  std::printf("processed %ld of %ld samples, dropped %ld; RSS after warm-up (%ld samples) "
              "%.1f MB, max after %.1f MB: growth %.1f MB (limit %.0f); %.0f samples/s\n",
              processed, o.samples, dropped, o.warmup, rss_warm, rss_max_after, growth,
              o.limit_mb, static_cast<double>(processed) / (seconds() - start));
  if (!last_warning.empty()) std::printf("last health warning: %s\n", last_warning.c_str());
  bool batch_ok = true;
  if (o.batch && run) {
    const BatchEstimate b = run->batch(timeline.roadHistoryComplete());
    std::printf("batch: %s\n", b.summary.c_str());
    batch_ok = b.ok;
  }
  return (dropped == 0 && processed == o.samples && growth < o.limit_mb && batch_ok) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(parse(argc, argv));
  } catch (const std::exception& e) {
    std::cerr << "soak_estimator: " << e.what() << "\n";
    return 2;
  }
}
