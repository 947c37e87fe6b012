// JSON and CSV output of estimate_offline (docs/method.md §8.3). The JSON
// comes from nlohmann::json: numbers in their shortest round-trip form (a
// reader gets the same double), strings escaped as JSON requires, non-finite
// numbers as null.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "pc_ekf/io/number_text.h"
#include "pc_ekf/io/offline_estimation.h"
#include "pc_ekf/io/samples_csv.h"

namespace pc_ekf {
namespace {

// Keys in the order of the documented output.
using Json = nlohmann::ordered_json;

// One safeguard's rate checks (docs/method.md §5.9).
Json rateJson(const SafeguardRate& r, bool per_second) {
  const auto span = [per_second](const RateCheck& c) {
    Json j;
    j["count"] = c.count;
    if (per_second) {
      j["exposure_s"] = c.exposure;
    } else {
      j["trials"] = c.trials;
    }
    j["expected"] = c.expected;
    j["p"] = c.tail;
    j["flagged"] = c.flagged;
    return j;
  };
  return {{"window", span(r.window)}, {"run", span(r.run)}, {"flagged", r.flagged()}};
}

Json numberList(const Eigen::VectorXd& v) {
  Json list = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) list.push_back(v[i]);
  return list;
}

void makeDirectory(const std::string& dir) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) {
    throw std::runtime_error(dir + ": cannot create the output directory (" + error.message() +
                             ")");
  }
}

// CSV numbers with max_digits10 significant digits: they read back as the
// same doubles, like the JSON's.
std::ofstream openOutput(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out << std::setprecision(std::numeric_limits<double>::max_digits10);
  return out;
}

}  // namespace

std::string toJson(const OfflineResult& r) {
  Json j;
  j["method"] = r.method;
  j["update"] = r.update;
  j["samples"] = r.samples;
  j["healthy"] = r.healthy;
  j["warnings"] = r.warnings;
  j["parameters"] = Json::array();
  for (const ParameterSummary& p : r.parameters) {
    j["parameters"].push_back({{"name", p.name},
                               {"mean", p.mean},
                               {"stddev", p.stddev},
                               {"xi_mean", p.xi_mean},
                               {"xi_stddev", p.xi_stddev}});
  }
  // Vehicles with heights (docs/tools.md): the rollover outputs, PC
  // expansions of the same germs as the parameters'; absent otherwise.
  if (!r.derived.empty()) {
    j["derived"] = Json::array();
    for (const DerivedSummary& d : r.derived) {
      j["derived"].push_back({{"name", d.name},
                              {"mean", d.mean},
                              {"stddev", d.stddev},
                              {"coefficients", numberList(d.coefficients)}});
    }
  }
  // Models that give it: the last sample's load transfer ratio (null: NaN).
  if (r.load_transfer_ratio) j["load_transfer_ratio"] = r.last_record.load_transfer_ratio;
  j["coherence"] = {{"available", r.coherence.available},
                    {"decimation", r.coherence.decimation},
                    {"disagreement", numberList(r.coherence.disagreement)},
                    {"threshold", r.coherence.threshold},
                    {"flagged", r.coherence.flagged}};
  j["nis_window_violations"] = r.nis_window_violations;
  j["band_nested_fraction"] = r.band_nested_fraction;
  j["integrations"] = r.integrations;
  j["wall_time_s"] = r.wall_seconds;
  j["predictive_check"] = {{"available", r.predictive.available},
                           {"statistic", r.predictive.statistic},
                           {"dof", r.predictive.dof},
                           {"lower", r.predictive.lower},
                           {"upper", r.predictive.upper},
                           {"spread", r.predictive.spread},
                           {"outside", r.predictive.outside}};
  // Each observed channel's mean normalised squared residual (1 under the model).
  Json per_channel = Json::object();
  for (std::size_t c = 0; c < r.predictive.channel_names.size(); ++c) {
    per_channel[r.predictive.channel_names[c]] = r.predictive.observed_mean[c];
  }
  j["predictive_check"]["channels"] = per_channel;
  if (!r.sensitivity.parameters.empty()) {
    Json rows = Json::array();
    for (int i : r.sensitivity.ranking()) {
      Json per_channel = Json::object();
      for (std::size_t c = 0; c < r.sensitivity.channels.size(); ++c) {
        per_channel[r.sensitivity.channels[c]] = r.sensitivity.total(i, static_cast<Eigen::Index>(c));
      }
      rows.push_back({{"name", r.sensitivity.parameters[i]},
                      {"largest_total", r.sensitivity.largestTotal(i)},
                      {"total", per_channel}});
    }
    j["sensitivity"] = rows;  // ranked, total Sobol indices of the prior's readings
    if (r.sensitivity.unexplained.size() > 0) {
      Json missed = Json::object();
      for (std::size_t c = 0; c < r.sensitivity.channels.size(); ++c) {
        missed[r.sensitivity.channels[c]] =
            r.sensitivity.unexplained(static_cast<Eigen::Index>(c));
      }
      j["sensitivity_unexplained"] = missed;  // leave-one-out share of each channel's variance
    }
    if (!r.sensitivity.expansion.empty()) {
      j["sensitivity_expansion"] = r.sensitivity.expansion;
      j["sensitivity_simulations"] = r.sensitivity.simulations;
    }
  }
  if (!r.pruned_tolerances.empty()) j["pruned_tolerances"] = r.pruned_tolerances;
  j["rejected_samples"] = r.rejected_samples;
  j["damped_updates"] = r.damped_updates;
  j["reopened"] = r.reopened;
  j["relinearized"] = r.relinearized;
  if (r.load_tracking) {
    nlohmann::json events = nlohmann::json::array();
    for (const LoadChangeEvent& e : r.load_changes) {
      nlohmann::json load = nlohmann::json::object();
      for (const ParameterSummary& p : e.load) load[p.name] = {{"mean", p.mean}, {"stddev", p.stddev}};
      events.push_back({{"began_s", e.began}, {"found_s", e.found}, {"load", load}});
    }
    j["load_changes"] = events;
  }
  if (std::isfinite(r.clock_offset)) {
    j["clock_offset"] = {{"mean_s", r.clock_offset}, {"stddev_s", r.clock_offset_std}};
  }
  if (!r.nuisance.empty()) {
    Json values = Json::object();
    for (const NuisanceValue& v : r.nuisance) values[v.name] = {{"mean", v.mean}, {"stddev", v.stddev}};
    j["nuisance"] = values;
  }
  if (r.method == "grid") {
    j["modes"] = r.modes;
    j["border_mass"] = r.border_mass;
  }
  // Appended (issue 33): the safeguards' rates at the last sample (one-step).
  const SafeguardRates& s = r.safeguard_rates;
  j["safeguard_rates"] = {{"available", s.available},
                          {"flagged", s.flagged()},
                          {"window_violations", r.rate_window_violations},
                          {"gated", rateJson(s.gated, false)},
                          {"damped", rateJson(s.damped, false)},
                          {"reopened", rateJson(s.reopened, true)},
                          {"support", rateJson(s.support, false)}};
  // Bytes that are not UTF-8 (a warning quoting a file) become U+FFFD
  // instead of an exception.
  return j.dump(1, ' ', false, Json::error_handler_t::replace) + "\n";
}

OfflineOutputs::OfflineOutputs(const std::string& dir) : dir_(dir) {
  makeDirectory(dir);
  // Never a previous run's result beside this run's rows.
  for (const char* name : {"/result.json", "/pdfs.csv"}) {
    std::error_code ignored;
    std::filesystem::remove(dir + name, ignored);
  }
  samples_ = std::make_unique<SamplesCsv>(dir + "/samples.csv");
}

OfflineOutputs::~OfflineOutputs() = default;

void OfflineOutputs::begin(const SampleColumns& columns) { samples_->begin(columns); }

void OfflineOutputs::add(SampleRecord record) { samples_->add(std::move(record)); }

void OfflineOutputs::finish(const OfflineResult& r) {
  SampleColumns columns;
  for (const ParameterSummary& p : r.parameters) columns.parameters.push_back(p.name);
  columns.loo_channels = r.loo_channels;
  columns.load_transfer_ratio = r.load_transfer_ratio;
  samples_->close(columns);

  std::string text = "parameter,bin_low,bin_high,density\n";
  for (std::size_t i = 0; i < r.pdfs.size() && i < r.parameters.size(); ++i) {
    const Histogram& h = r.pdfs[i];
    for (Eigen::Index b = 0; b < h.densities.size(); ++b) {
      text += r.parameters[i].name;
      for (double v : {h.edges[b], h.edges[b + 1], h.densities[b]}) {
        text += ',';
        appendG17(text, v);
      }
      text += '\n';
    }
  }
  // The derived quantities' PDFs after the parameters' (vehicles with heights).
  for (const DerivedSummary& d : r.derived) {
    for (Eigen::Index b = 0; b < d.pdf.densities.size(); ++b) {
      text += d.name;
      for (double v : {d.pdf.edges[b], d.pdf.edges[b + 1], d.pdf.densities[b]}) {
        text += ',';
        appendG17(text, v);
      }
      text += '\n';
    }
  }
  std::ofstream pdfs = openOutput(dir_ + "/pdfs.csv");
  pdfs << text;
  pdfs.close();
  std::ofstream json = openOutput(dir_ + "/result.json");
  json << toJson(r);
  json.close();
  if (!pdfs || !json) throw std::runtime_error(dir_ + ": writing the outputs failed");
}

}  // namespace pc_ekf
