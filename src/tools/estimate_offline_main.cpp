// estimate_offline: any estimator on a CSV, bag or synthetic record, no ROS
// master needed. One JSON object on stdout; logs on stderr; exit 2 on bad input.
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "pc_ekf/io/config_identity.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/io/measurement_csv.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/tools/command_line.h"
#include "pc_ekf/tools/heap_settings.h"
#include "pc_ekf/tools/record_input.h"

namespace {

const char* kUsage =
    "usage: estimate_offline --config FILE.yaml [--measurements FILE.csv | --bag FILE.bag]\n"
    "                        [--method one_step|whole_set|es_mda|enkf|grid]\n"
    "                        [--update paper|square_root] [--seed N] [--out DIR]\n"
    "                        [--sensitivity]\n"
    "       estimate_offline --config FILE.yaml --config-hash\n"
    "  --sensitivity: total Sobol indices of every uncertain parameter on each observed\n"
    "  channel (whole-record runs of the prior), a ranked table on stderr and in the JSON\n"
    "  --config-hash: only check the config and print its identity (0x + 16 hex digits:\n"
    "  the config with its vehicle file's contents, as the node's checkpoints hold it)\n";

}  // namespace

int main(int argc, char** argv) {
  using namespace pc_ekf;
  keepFreedHeap();
  CommandLine args("estimate_offline", kUsage);
  const int parsed = args.parse(
      argc, argv, {"--config", "--measurements", "--bag", "--method", "--update", "--seed", "--out"},
      {"--sensitivity", "--config-hash"});
  if (parsed >= 0) return parsed;
  if (!args.has("--config")) return args.badInput(std::string("--config is required\n") + kUsage);
  if (args.has("--measurements") && args.has("--bag")) {
    return args.badInput("give either --measurements or --bag, not both");
  }
  return args.run([&] {
    if (args.has("--config-hash")) {
      std::cout << hashText(configFileHash(args["--config"], modelRegistryOnDemand())) << "\n";
      return 0;
    }
    EstimatorConfig config = loadConfigFile(args["--config"], modelRegistryOnDemand());
    if (args.has("--update")) config.update = updateRuleFromString(args["--update"]);
    const EstimationMethod method =
        estimationMethodFromString(args.has("--method") ? args["--method"] : "one_step");
    std::uint64_t given_seed = 0;
    int status = 0;
    if (args.has("--seed") && !args.unsignedValue("--seed", &given_seed, &status)) return status;
    const std::uint64_t seed = runSeed(config, args.has("--bag") || args.has("--measurements"),
                                       args.has("--seed") ? &given_seed : nullptr);
    // Road-free one-step splits the readings as the filter goes, a bag's
    // or CSV's read as a stream (memory independent of the record's
    // length); the other methods, the sensitivity and tolerances_prune need
    // the whole split first.
    const bool stream_road_free = config.road.source == RoadSource::kNone &&
                                  method == EstimationMethod::kOneStep &&
                                  !args.has("--sensitivity") && !(config.tolerances_prune > 0.0);
    const std::string bag = args.has("--bag") ? args["--bag"] : "";
    const std::string csv = args.has("--measurements") ? args["--measurements"] : "";
    std::optional<StreamedRecord> streamed;
    if (stream_road_free) streamed = streamRoadFreeRecord(config, bag, csv);
    const RecordInput record =
        streamed ? RecordInput() : loadRecord(config, bag, csv, seed, !stream_road_free);
    const auto& model = record.model;
    const MeasurementSeries& series = record.series;
    PriorSensitivity sensitivity;
    std::vector<std::string> pruned;
    config = sensitivityAndPrune(config, record, args.has("--sensitivity"), &sensitivity, &pruned);
    const auto progress = [](const std::string& msg) { std::cerr << "[progress] " << msg << "\n"; };
    // --out: the rows are written as the run makes them (none is kept).
    std::unique_ptr<OfflineOutputs> out;
    if (args.has("--out")) out = std::make_unique<OfflineOutputs>(args["--out"]);
    OfflineResult result =
        streamed           ? runRoadFreeOneStep(config, *streamed->stream, streamed->checked, out.get())
        : stream_road_free ? runRoadFreeOneStep(config, series, out.get(), record.interval)
                           : runOfflineEstimation(config, series, model, method, seed, progress,
                                                  nullptr, out.get());
    const std::vector<std::string>& warnings = streamed ? streamed->warnings : record.warnings;
    result.warnings.insert(result.warnings.begin(), warnings.begin(), warnings.end());
    if (args.has("--sensitivity")) result.sensitivity = sensitivity;
    result.pruned_tolerances = pruned;
    std::cout << toJson(result) << std::flush;
    if (out) out->finish(result);
    return 0;
  });
}
