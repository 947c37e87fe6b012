// ISO 8608 rough roads and measured profiles by distance (road_profile.h).
#include "pc_ekf/model/road_profile.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "pc_ekf/model/smooth_functions.h"

namespace pc_ekf {

namespace {

constexpr double kPi = 3.14159265358979323846;

// One track's harmonics at distance s, sum of amplitude sin(wavenumber s +
// phase). The terms in blocks (a loop the x86-64-v3 clone vectorises), the
// sum in index order, so that every build adds them the same way.
__attribute__((target_clones("arch=x86-64-v3", "default"))) double sumOfHarmonics(
    const double* __restrict amplitude, const double* __restrict wavenumber,
    const double* __restrict phase, std::size_t n, double s) {
  constexpr std::size_t kBlock = 64;
  double term[kBlock];
  double sum = 0.0;
  for (std::size_t start = 0; start < n; start += kBlock) {
    const std::size_t m = std::min(kBlock, n - start);
    for (std::size_t k = 0; k < m; ++k) {
      term[k] = amplitude[start + k] * fastSin(wavenumber[start + k] * s + phase[start + k]);
    }
    for (std::size_t k = 0; k < m; ++k) sum += term[k];
  }
  return sum;
}

}  // namespace

double iso8608LeadIn(double s, double length) {
  if (length <= 0.0 || s >= length) return s < 0.0 ? 0.0 : 1.0;
  if (s <= 0.0) return 0.0;
  const double x = s / length;
  return x * x * (3.0 - 2.0 * x);
}

double iso8608Roughness(char road_class) {
  if (road_class < 'A' || road_class > 'E') {
    throw std::invalid_argument(std::string("ISO 8608 class '") + road_class +
                                "': expected A, B, C, D or E");
  }
  return 16e-6 * std::pow(4.0, road_class - 'A');
}

Iso8608Profile::Iso8608Profile(const Iso8608Settings& s) : s_(s) {
  const double g0 = iso8608Roughness(s.road_class);
  if (!(s.n_min > 0.0 && s.n_max > s.n_min && s.bands >= 1)) {
    throw std::invalid_argument("ISO 8608 road: need 0 < n_min < n_max and bands >= 1");
  }
  if (!(s.correlation >= 0.0 && s.correlation <= 1.0)) {
    throw std::invalid_argument("ISO 8608 road: correlation must be in [0, 1]");
  }
  std::mt19937_64 rng(s.seed);
  std::uniform_real_distribution<double> uniform(0.0, 2.0 * kPi);
  const double ratio = std::log(s.n_max / s.n_min) / s.bands;
  for (int k = 0; k < s.bands; ++k) {
    const double lo = s.n_min * std::exp(ratio * k), hi = s.n_min * std::exp(ratio * (k + 1));
    const double n = std::sqrt(lo * hi), dn = hi - lo;
    const double gd = g0 * (0.1 / n) * (0.1 / n);  // waviness w = 2
    wavenumber_.push_back(2.0 * kPi * n);
    amplitude_.push_back(std::sqrt(2.0 * gd * dn));
  }
  for (auto& p : phase_) {
    for (int k = 0; k < s.bands; ++k) p.push_back(uniform(rng));
  }
}

double Iso8608Profile::height(int track, double s) const {
  if (s <= 0.0) return 0.0;
  double own[2] = {0.0, 0.0};
  for (int t = 0; t < (track == 0 ? 1 : 2); ++t) {
    own[t] = sumOfHarmonics(amplitude_.data(), wavenumber_.data(), phase_[t].data(),
                            wavenumber_.size(), s);
  }
  const double c = s_.correlation;
  const double h = track == 0 ? own[0] : c * own[0] + std::sqrt(1.0 - c * c) * own[1];
  return iso8608LeadIn(s, s_.lead_in) * h;
}

Eigen::Vector2d Iso8608Profile::bothTracks(double s) const {
  if (s <= 0.0) return Eigen::Vector2d::Zero();
  double own[2] = {0.0, 0.0};
  for (int t = 0; t < 2; ++t) {
    own[t] = sumOfHarmonics(amplitude_.data(), wavenumber_.data(), phase_[t].data(),
                            wavenumber_.size(), s);
  }
  const double c = s_.correlation, lead = iso8608LeadIn(s, s_.lead_in);
  return {lead * own[0], lead * (c * own[0] + std::sqrt(1.0 - c * c) * own[1])};
}

MeasuredProfile::MeasuredProfile(std::vector<double> s, std::vector<double> left,
                                 std::vector<double> right)
    : s_(std::move(s)), h_{std::move(left), std::move(right)} {
  if (s_.size() < 2 || h_[0].size() != s_.size() || h_[1].size() != s_.size()) {
    throw std::invalid_argument("measured road profile: at least two samples of s, left, right");
  }
  const double s0 = s_.front();
  for (std::size_t i = 0; i < s_.size(); ++i) {
    if (!std::isfinite(s_[i]) || !std::isfinite(h_[0][i]) || !std::isfinite(h_[1][i])) {
      throw std::invalid_argument("measured road profile: sample " + std::to_string(i) +
                                  " is not finite");
    }
    if (i > 0 && !(s_[i] > s_[i - 1])) {
      throw std::invalid_argument("measured road profile: distance at sample " +
                                  std::to_string(i) + " does not increase");
    }
  }
  for (double& v : s_) v -= s0;
}

double MeasuredProfile::height(int track, double s) const {
  const std::vector<double>& h = h_[track == 0 ? 0 : 1];
  if (s <= s_.front()) return h.front();
  if (s >= s_.back()) return h.back();
  const std::size_t i = std::upper_bound(s_.begin(), s_.end(), s) - s_.begin() - 1;
  const double w = (s - s_[i]) / (s_[i + 1] - s_[i]);
  return h[i] + w * (h[i + 1] - h[i]);
}

std::vector<double> MeasuredProfile::kinks(double s0, double s1) const {
  const auto first = std::upper_bound(s_.begin(), s_.end(), s0);
  const auto last = std::lower_bound(s_.begin(), s_.end(), s1);
  if (first >= last) return {};
  return std::vector<double>(first, last);
}

std::shared_ptr<const MeasuredProfile> readMeasuredProfileCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open the road profile");
  std::string line;
  int number = 0;
  std::vector<double> s, left, right;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (s.empty() && left.empty() && number >= 1 && line.find('s') != std::string::npos &&
        line.find("left") != std::string::npos) {
      std::string h;
      for (char ch : line) {
        if (ch != ' ' && ch != '\r') h += ch;
      }
      if (h != "s,left,right") {
        throw std::invalid_argument(path + ": line " + std::to_string(number) + ": header '" +
                                    line + "', expected 's,left,right'");
      }
      continue;
    }
    std::istringstream row(line);
    row.imbue(std::locale::classic());
    double v[3];
    char comma = 0;
    if (!(row >> v[0] >> comma) || comma != ',' || !(row >> v[1] >> comma) || comma != ',' ||
        !(row >> v[2])) {
      throw std::invalid_argument(path + ": line " + std::to_string(number) +
                                  ": expected three numbers s,left,right (m)");
    }
    s.push_back(v[0]);
    left.push_back(v[1]);
    right.push_back(v[2]);
  }
  try {
    return std::make_shared<const MeasuredProfile>(s, left, right);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

DrivenProfileRoad::DrivenProfileRoad(std::shared_ptr<const TrackProfile> profile, double speed,
                                     std::vector<std::pair<int, double>> contacts)
    : profile_(std::move(profile)), speed_(speed), contacts_(std::move(contacts)) {
  if (!profile_) throw std::invalid_argument("driven road: no profile");
  if (!(speed_ > 0.0) || !std::isfinite(speed_)) {
    throw std::invalid_argument("driven road: speed must be > 0");
  }
}

void DrivenProfileRoad::heights(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  if (contacts_.size() == 2 && contacts_[0].first == 0 && contacts_[1].first == 1 &&
      contacts_[0].second == contacts_[1].second) {  // both tracks at one distance
    out = profile_->bothTracks(speed_ * t - contacts_[0].second);
    return;
  }
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    out[static_cast<Eigen::Index>(c)] =
        profile_->height(contacts_[c].first, speed_ * t - contacts_[c].second);
  }
}

std::vector<double> DrivenProfileRoad::breakpoints(double t0, double t1) const {
  std::vector<double> out;
  for (const auto& [track, lag] : contacts_) {
    for (double s : profile_->kinks(speed_ * t0 - lag, speed_ * t1 - lag)) {
      out.push_back((s + lag) / speed_);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace pc_ekf
