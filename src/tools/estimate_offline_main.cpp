// estimate_offline: any estimator on a CSV, bag or synthetic record, no ROS
// master needed. One JSON object on stdout; logs on stderr; exit 2 on bad input.
#include <cstdlib>
#include <iostream>
#include <map>
#include <string>

#include "io/bag_io.h"
#include "io/estimation_setup.h"
#include "io/measurement_csv.h"
#include "io/offline_estimation.h"

namespace {

const char* kUsage =
    "usage: estimate_offline --config FILE.yaml [--measurements FILE.csv | --bag FILE.bag]\n"
    "                        [--method one_step|whole_set|es_mda|enkf|grid]\n"
    "                        [--update paper|square_root] [--seed N] [--out DIR]\n";

int badInput(const std::string& reason) {
  std::cerr << "estimate_offline: " << reason << "\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pc_ekf;
  std::map<std::string, std::string> args;
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    if (key == "-h" || key == "--help") {
      std::cout << kUsage;
      return 0;
    }
    static const char* known[] = {"--config", "--measurements", "--bag", "--method",
                                  "--update", "--seed", "--out"};
    bool ok = false;
    for (const char* k : known) ok = ok || key == k;
    if (!ok) return badInput("unknown option '" + key + "'\n" + kUsage);
    if (i + 1 >= argc) return badInput("option " + key + " needs a value");
    args[key] = argv[++i];
  }
  if (!args.count("--config")) return badInput(std::string("--config is required\n") + kUsage);
  if (args.count("--measurements") && args.count("--bag")) {
    return badInput("give either --measurements or --bag, not both");
  }
  try {
    EstimatorConfig config = loadConfigFile(args["--config"]);
    if (args.count("--update")) config.update = updateRuleFromString(args["--update"]);
    const EstimationMethod method =
        estimationMethodFromString(args.count("--method") ? args["--method"] : "one_step");
    std::uint64_t seed = config.truth.seed;
    if (args.count("--seed")) {
      const std::string& s = args["--seed"];
      if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 19) {
        return badInput("--seed '" + s + "' is not a non-negative integer");
      }
      seed = std::stoull(s);
    }
    // A bag supplies the road (replacing the config's) and the samples.
    std::shared_ptr<const RoadInput> bag_road;
    MeasurementSeries series;
    if (args.count("--bag")) {
      BagRecord bag = readBag(args["--bag"]);
      for (std::size_t i = 0; i < bag.warnings.size() && i < 5; ++i) {
        std::cerr << "[bag] " << args["--bag"] << ": " << bag.warnings[i] << "\n";
      }
      if (bag.warnings.size() > 5) {
        std::cerr << "[bag] ... and " << bag.warnings.size() - 5 << " more warnings\n";
      }
      bag_road = std::make_shared<SampledRoad>(bag.road.t, bag.road.left, bag.road.right);
      series = std::move(bag.samples);
    }
    const auto model = makeModel(config, makeRoad(config, bag_road));
    if (args.count("--measurements")) series = readMeasurementCsvFile(args["--measurements"]);
    if (!args.count("--measurements") && !args.count("--bag")) {
      series = synthesizeFromConfig(config, *model, seed);
    }
    const auto progress = [](const std::string& msg) { std::cerr << "[progress] " << msg << "\n"; };
    const OfflineResult result = runOfflineEstimation(config, series, model, method, seed, progress);
    std::cout << toJson(result) << std::flush;
    if (args.count("--out")) writeOfflineOutputs(result, args["--out"]);
    return 0;
  } catch (const ConfigError& e) {
    return badInput(e.what());
  } catch (const CsvError& e) {
    return badInput(e.what());
  } catch (const BagError& e) {
    return badInput(e.what());
  } catch (const std::invalid_argument& e) {
    return badInput(e.what());
  } catch (const std::exception& e) {
    std::cerr << "estimate_offline: error: " << e.what() << "\n";
    return 1;
  }
}
