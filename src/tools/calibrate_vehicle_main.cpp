// calibrate_vehicle: estimates the vehicle values listed under tolerances: on
// records with a known load and writes a vehicle file (every value of the
// model, and the remaining tolerances) for later runs' `vehicle_file:`.
// Exit 0 written, 2 bad input, 3 calibration unhealthy (nothing written).
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "pc_ekf/io/atomic_file.h"
#include "pc_ekf/io/calibration.h"
#include "pc_ekf/tools/command_line.h"
#include "pc_ekf/tools/record_input.h"

namespace {

const char* kUsage =
    "usage: calibrate_vehicle --config FILE.yaml (--measurements F.csv | --bag F.bag) ...\n"
    "                         [--method es_mda|one_step] [--update paper|square_root]\n"
    "                         [--seed N] [--force] --out VEHICLE.yaml\n"
    "  The config sets the known load in vehicle: (added_mass, added_mass_position) and\n"
    "  lists the values to calibrate under tolerances:. Several records may be given,\n"
    "  each after the --config it is read with (e.g. two ballasts: --config a.yaml --bag\n"
    "  a.bag --config b.yaml --bag b.bag); they are used one after another. Without a\n"
    "  record the config's synthetic data are used (trials). An unhealthy calibration\n"
    "  writes nothing and exits 3 unless --force is given.\n";

struct Source {
  std::string config, bag, csv;
};

// The config's vehicle: section as (key, scalar text), vehicle_file merged.
std::vector<std::pair<std::string, std::string>> vehicleKeys(const std::string& config_path) {
  YAML::Node root = YAML::LoadFile(config_path);
  pc_ekf::anchorVehicleFile(root, config_path);
  root = pc_ekf::mergeVehicleFile(root, config_path, nullptr);
  std::vector<std::pair<std::string, std::string>> out;
  const YAML::Node v = root["vehicle"];
  if (!v || !v.IsMap()) return out;
  for (const auto& kv : v) {
    if (kv.second.IsScalar()) out.emplace_back(kv.first.Scalar(), kv.second.Scalar());
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pc_ekf;
  CommandLine cli("calibrate_vehicle", kUsage);
  std::vector<Source> sources;
  std::string method_name = "one_step", update, out_path, seed_text;
  bool force = false;
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    if (key == "-h" || key == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (key == "--force") {
      force = true;
      continue;
    }
    if (i + 1 >= argc) return cli.badInput("option " + key + " needs a value");
    const std::string value = argv[++i];
    if (key == "--config") {
      sources.push_back({value, "", ""});
    } else if (key == "--bag" || key == "--measurements") {
      if (sources.empty()) return cli.badInput(key + " " + value + " before any --config");
      Source& s = sources.back();
      if (!s.bag.empty() || !s.csv.empty()) sources.push_back({s.config, "", ""});
      (key == "--bag" ? sources.back().bag : sources.back().csv) = value;
    } else if (key == "--method") {
      method_name = value;
    } else if (key == "--update") {
      update = value;
    } else if (key == "--seed") {
      seed_text = value;
    } else if (key == "--out") {
      out_path = value;
    } else {
      return cli.badInput("unknown option '" + key + "'\n" + kUsage);
    }
  }
  if (sources.empty()) return cli.badInput(std::string("--config is required\n") + kUsage);
  if (out_path.empty()) return cli.badInput(std::string("--out VEHICLE.yaml is required\n") + kUsage);
  if (method_name != "one_step" && method_name != "es_mda") {
    return cli.badInput("--method '" + method_name + "': calibration runs one_step or es_mda");
  }
  return cli.run([&] {
    const EstimationMethod method = estimationMethodFromString(method_name);
    std::vector<CalibrationRecord> records;
    std::uint64_t seed = 0;
    for (const Source& s : sources) {
      EstimatorConfig config = loadConfigFile(s.config, modelRegistryOnDemand());
      if (!update.empty()) config.update = updateRuleFromString(update);
      checkCalibrationConfig(config, records.empty() ? nullptr : &records.front().config);
      const std::uint64_t given = seed_text.empty() ? 0 : std::stoull(seed_text);
      seed = runSeed(config, !s.bag.empty() || !s.csv.empty(),
                     seed_text.empty() ? nullptr : &given);
      RecordInput in = loadRecord(config, s.bag, s.csv, seed);
      PriorSensitivity sensitivity;
      std::vector<std::string> pruned;
      if (records.empty()) {
        config = sensitivityAndPrune(config, in, true, &sensitivity, &pruned);
      } else if (config.tolerances_prune > 0.0) {  // the first record's choice holds for all
        const auto& first = records.front().config.uncertain;
        std::vector<UncertainParameter> kept;
        for (const auto& u : config.uncertain) {
          for (const auto& f : first) {
            if (f.name == u.name) kept.push_back(u);
          }
        }
        config.uncertain = kept;
        config.tolerance_count = static_cast<int>(kept.size());
      }
      const std::string label = !s.bag.empty()   ? "bag " + s.bag
                                : !s.csv.empty() ? "measurements " + s.csv
                                                 : "synthetic data of " + s.config;
      records.push_back({std::move(config), std::move(in.series), std::move(in.model), label});
    }
    const auto progress = [](const std::string& msg) { std::cerr << "[progress] " << msg << "\n"; };
    const EstimatorConfig last = records.back().config;
    std::vector<std::string> labels;
    for (const auto& r : records) labels.push_back(r.label + " (config " + r.config.source + ")");
    const CalibrationResult result = calibrate(std::move(records), method, seed, progress);

    std::vector<std::string> header{"Vehicle file written by calibrate_vehicle (pc_ekf); merge it",
                                    "into a config with `vehicle_file: <this file>`.",
                                    "method: " + method_name + " (" + result.runs.back().update + ")"};
    for (std::size_t k = 0; k < labels.size(); ++k) {
      const OfflineResult& run = result.runs[k];
      header.push_back("record " + std::to_string(k + 1) + ": " + labels[k]);
      header.push_back("  samples " + std::to_string(run.samples) + ", healthy " +
                       (run.healthy ? "true" : "false"));
      for (const auto& w : run.warnings) header.push_back("  warning: " + w);
    }
    header.push_back(std::string("calibration healthy: ") + (result.healthy ? "true" : "false") +
                     (result.healthy ? "" : " (written with --force)"));
    header.push_back("tolerances: the calibration posterior, moment-matched (same germs): this");
    header.push_back("prior has its mean and standard deviation.");
    if (!result.healthy && !force) {
      std::cerr << "calibrate_vehicle: the calibration run is unhealthy";
      for (const auto& run : result.runs) {
        for (const auto& w : run.warnings) std::cerr << "; " << w;
      }
      std::cerr << "; nothing written to " << out_path
                << " (--force writes it anyway; check the known load and the records first)\n";
      return 3;
    }
    const VehicleFile file =
        calibratedVehicleFile(result, last, vehicleKeys(last.source), header);
    writeFileAtomically(out_path, vehicleFileText(file));
    for (const auto& u : result.tolerances) {
      std::cerr << "[calibrated] " << u.name << " = " << roundTripText(u.nominal) << " +- "
                << u.nominal * u.relative_range * germStddev(u.germ) << "\n";
    }
    std::cerr << "[calibrated] wrote " << out_path << "\n";
    return 0;
  });
}
