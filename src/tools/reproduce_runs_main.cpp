// reproduce_runs: the runs behind launch_free_scripts/reproduce.sh. For one
// configuration and sample count it synthesises the data of every seed and
// runs each requested method on it through runOfflineEstimation, the same
// code path as estimate_offline, printing one JSON line per run. The grid
// posterior's coarse-grid simulations are built once (they do not depend on
// the data).
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "pc_ekf/reference/reference_posterior.h"
#include "pc_ekf/filter/synthetic_data.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/ros/model_plugins.h"
#include "pc_ekf/io/offline_estimation.h"

namespace {

using namespace pc_ekf;

const char* kUsage =
    "usage: reproduce_runs --config FILE.yaml --samples N --seeds FIRST-LAST --dataset NAME\n"
    "                      [--methods LIST] [--enkf-members SMALL,LARGE] [--threads K]\n"
    "                      [--per-sample-dir DIR]\n"
    "  LIST: comma-separated of one_step_paper, one_step_square_root, whole_set_paper,\n"
    "        whole_set_square_root, es_mda, enkf_small, enkf_large, grid (default: all)\n";

struct MethodRun {
  EstimationMethod method;
  UpdateRule rule;
  int enkf_members = 0;  // 0: keep the config's
};

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, sep);) out.push_back(item);
  return out;
}

int usage(const std::string& why) {
  std::cerr << "reproduce_runs: " << why << "\n" << kUsage;
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::map<std::string, std::string> a;
  for (int i = 1; i + 1 < argc; i += 2) a[argv[i]] = argv[i + 1];
  if (argc % 2 == 0 || !a.count("--config") || !a.count("--samples") || !a.count("--seeds") ||
      !a.count("--dataset")) {
    return usage("missing or unpaired arguments");
  }
  try {
    EstimatorConfig config = loadConfigFile(a["--config"], modelRegistryWithPlugins());
    config.sampling.samples = std::stoi(a["--samples"]);
    const auto seeds = split(a["--seeds"], '-');
    const std::uint64_t first = std::stoull(seeds.at(0)), last = std::stoull(seeds.at(1));
    const auto members = split(a.count("--enkf-members") ? a["--enkf-members"] : "200,2000", ',');
    config.grid.threads = a.count("--threads") ? std::stoi(a["--threads"]) : 1;
    const std::map<std::string, MethodRun> known{
        {"one_step_paper", {EstimationMethod::kOneStep, UpdateRule::kPaper}},
        {"one_step_square_root", {EstimationMethod::kOneStep, UpdateRule::kSquareRoot}},
        {"whole_set_paper", {EstimationMethod::kWholeSet, UpdateRule::kPaper}},
        {"whole_set_square_root", {EstimationMethod::kWholeSet, UpdateRule::kSquareRoot}},
        {"es_mda", {EstimationMethod::kEsMda, UpdateRule::kSquareRoot}},
        {"enkf_small", {EstimationMethod::kEnkf, UpdateRule::kSquareRoot, std::stoi(members.at(0))}},
        {"enkf_large", {EstimationMethod::kEnkf, UpdateRule::kSquareRoot, std::stoi(members.at(1))}},
        {"grid", {EstimationMethod::kGrid, UpdateRule::kSquareRoot}}};
    std::vector<std::string> labels;
    if (a.count("--methods")) {
      labels = split(a["--methods"], ',');
    } else {
      for (const auto& [label, run] : known) labels.push_back(label);
    }
    for (const auto& l : labels) {
      if (!known.count(l)) return usage("unknown method '" + l + "'");
    }

    const auto model = makeModel(config, makeRoad(config));
    std::unique_ptr<CoarseGridCache> cache;
    for (const auto& l : labels) {
      if (l != "grid") continue;
      cache = std::make_unique<CoarseGridCache>(
          *model, ParameterMapping(*model, config.uncertain),
          syntheticSampleTimes(config), config.integration,
          config.grid.coarse_points, config.grid.threads);
    }
    for (std::uint64_t seed = first; seed <= last; ++seed) {
      const MeasurementSeries data = synthesizeFromConfig(config, *model, seed);
      for (const auto& label : labels) {
        const MethodRun& run = known.at(label);
        EstimatorConfig c = config;
        c.update = run.rule;
        if (run.enkf_members > 0) c.enkf.members = run.enkf_members;
        // The first seed's rows go to --per-sample-dir as they are made.
        std::unique_ptr<OfflineOutputs> per_sample;
        if (a.count("--per-sample-dir") && seed == first) {
          per_sample = std::make_unique<OfflineOutputs>(a["--per-sample-dir"] + "/" +
                                                        a["--dataset"] + "/" + label);
        }
        const OfflineResult r = runOfflineEstimation(c, data, model, run.method, seed, {},
                                                     cache.get(), per_sample.get());
        std::string json = toJson(r);
        while (!json.empty() && json.back() == '\n') json.pop_back();
        for (auto& ch : json) if (ch == '\n') ch = ' ';
        std::cout << "{\"dataset\": \"" << a["--dataset"] << "\", \"samples\": "
                  << config.sampling.samples << ", \"seed\": " << seed << ", \"label\": \"" << label
                  << "\", \"members\": " << c.enkf.members << ", \"result\": " << json << "}"
                  << std::endl;
        if (per_sample) per_sample->finish(r);
      }
      std::cerr << "[progress] " << a["--dataset"] << " seed " << seed << " done\n";
    }
    return 0;
  } catch (const ConfigError& e) {
    return usage(e.what());
  } catch (const std::exception& e) {
    std::cerr << "reproduce_runs: error: " << e.what() << "\n";
    return 1;
  }
}
