// JSON and CSV output of estimate_offline (INTERFACE.md).
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/io/offline_estimation.h"

namespace pc_ekf {
namespace {

std::string number(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream o;
  o << std::setprecision(12) << v;
  return o.str();
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"' || ch == '\\') out += '\\';
    if (static_cast<unsigned char>(ch) < 0x20) {
      out += ' ';
      continue;
    }
    out += ch;
  }
  return out + "\"";
}

std::string numberList(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += (i ? ", " : "") + number(v[i]);
  return s + "]";
}

void makeDirectory(const std::string& dir) {
  std::string path;
  std::istringstream parts(dir);
  std::string part;
  if (!dir.empty() && dir[0] == '/') path = "/";
  while (std::getline(parts, part, '/')) {
    if (part.empty()) continue;
    path += part + "/";
    if (mkdir(path.c_str(), 0755) != 0 && errno != EEXIST) {
      throw std::runtime_error(dir + ": cannot create the output directory (" +
                               std::strerror(errno) + ")");
    }
  }
}

std::ofstream openOutput(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out << std::setprecision(15);
  return out;
}

}  // namespace

std::string toJson(const OfflineResult& r) {
  std::ostringstream o;
  o << "{\"method\": " << quoted(r.method) << ", \"update\": " << quoted(r.update)
    << ", \"samples\": " << r.samples << ", \"healthy\": " << (r.healthy ? "true" : "false")
    << ",\n \"warnings\": [";
  for (std::size_t i = 0; i < r.warnings.size(); ++i) o << (i ? ", " : "") << quoted(r.warnings[i]);
  o << "],\n \"parameters\": [";
  for (std::size_t i = 0; i < r.parameters.size(); ++i) {
    const ParameterSummary& p = r.parameters[i];
    o << (i ? ",\n   " : "\n   ") << "{\"name\": " << quoted(p.name) << ", \"mean\": " << number(p.mean)
      << ", \"stddev\": " << number(p.stddev) << ", \"xi_mean\": " << number(p.xi_mean)
      << ", \"xi_stddev\": " << number(p.xi_stddev) << "}";
  }
  o << "],\n \"coherence\": {\"available\": " << (r.coherence.available ? "true" : "false")
    << ", \"decimation\": " << r.coherence.decimation
    << ", \"disagreement\": " << numberList(r.coherence.disagreement)
    << ", \"threshold\": " << number(r.coherence.threshold)
    << ", \"flagged\": " << (r.coherence.flagged ? "true" : "false") << "},\n"
    << " \"nis_window_violations\": " << r.nis_window_violations
    << ", \"band_nested_fraction\": " << number(r.band_nested_fraction)
    << ", \"integrations\": " << r.integrations << ", \"wall_time_s\": " << number(r.wall_seconds)
    << ",\n \"predictive_check\": {\"available\": " << (r.predictive.available ? "true" : "false")
    << ", \"statistic\": " << number(r.predictive.statistic) << ", \"dof\": " << r.predictive.dof
    << ", \"lower\": " << number(r.predictive.lower) << ", \"upper\": " << number(r.predictive.upper)
    << ", \"outside\": " << (r.predictive.outside ? "true" : "false") << "},\n"
    << " \"rejected_samples\": " << r.rejected_samples << ", \"damped_updates\": " << r.damped_updates
    << ", \"reopened\": " << r.reopened;
  if (r.method == "grid") {
    o << ", \"modes\": " << r.modes << ", \"border_mass\": " << number(r.border_mass);
  }
  o << "}\n";
  return o.str();
}

void writeOfflineOutputs(const OfflineResult& r, const std::string& dir) {
  makeDirectory(dir);
  std::ofstream json = openOutput(dir + "/result.json");
  json << toJson(r);

  std::ofstream samples = openOutput(dir + "/samples.csv");
  samples << "index,t";
  const int terms = r.records.empty() ? 0 : static_cast<int>(r.records[0].coefficients.cols());
  for (const auto& p : r.parameters) {
    samples << ',' << p.name << "_mean," << p.name << "_stddev";
    for (int j = 0; j < terms; ++j) samples << ',' << p.name << "_c" << j;
  }
  samples << ",nis,nis_window_outside,band_nested,healthy";
  for (const auto& channel : r.loo_channels) samples << ",loo_" << channel;
  samples << '\n';
  for (const SampleRecord& s : r.records) {
    samples << s.index << ',' << s.time;
    for (Eigen::Index i = 0; i < s.mean.size(); ++i) {
      samples << ',' << s.mean[i] << ',' << s.stddev[i];
      for (int j = 0; j < terms; ++j) samples << ',' << s.coefficients(i, j);
    }
    samples << ',' << s.nis << ',' << s.nis_window_outside << ',' << s.band_nested << ','
            << s.healthy;
    // Empty cells: no leave-one-out error for this sample (a point left out).
    for (std::size_t i = 0; i < r.loo_channels.size(); ++i) {
      samples << ',';
      if (static_cast<std::size_t>(s.loo_error.size()) == r.loo_channels.size())
        samples << s.loo_error[i];
    }
    samples << '\n';
  }

  std::ofstream pdfs = openOutput(dir + "/pdfs.csv");
  pdfs << "parameter,bin_low,bin_high,density\n";
  for (std::size_t i = 0; i < r.pdfs.size() && i < r.parameters.size(); ++i) {
    const Histogram& h = r.pdfs[i];
    for (Eigen::Index b = 0; b < h.densities.size(); ++b) {
      pdfs << r.parameters[i].name << ',' << h.edges[b] << ',' << h.edges[b + 1] << ','
           << h.densities[b] << '\n';
    }
  }
  if (!samples || !pdfs || !json) throw std::runtime_error(dir + ": writing the outputs failed");
}

}  // namespace pc_ekf
