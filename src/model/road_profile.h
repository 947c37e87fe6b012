// Roads given by distance along two tracks (left, right), driven at a
// constant speed: an ISO 8608 rough road for simulation, and a measured
// profile (CSV s,left,right). docs/method.md §1.5.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "pc_ekf/model/road_input.h"

namespace pc_ekf {

// Heights (m, up positive) of the left (0) and right (1) track at distance s.
class TrackProfile {
 public:
  virtual ~TrackProfile() = default;
  virtual double height(int track, double s) const = 0;
  // Both tracks at one distance (left, right): height(0, s), height(1, s).
  virtual Eigen::Vector2d bothTracks(double s) const { return {height(0, s), height(1, s)}; }
  // Distances in (s0, s1) where the profile has a kink.
  virtual std::vector<double> kinks(double s0, double s1) const = 0;
};

// ISO 8608 roughness (Iso8608Settings, road_input.h: the PSD, the sum of
// sinusoids, the tracks' correlation and the lead-in).
// Gd(n0) of a class, m^3; throws std::invalid_argument outside A..E.
double iso8608Roughness(char road_class);

// The lead-in weight of Iso8608Profile at distance s: 0 up to 0, 1 from
// `lead_in` on, a C1 cubic step between (lead_in 0: a step at 0).
double iso8608LeadIn(double s, double lead_in);

class Iso8608Profile : public TrackProfile {
 public:
  explicit Iso8608Profile(const Iso8608Settings& s);
  double height(int track, double s) const override;
  // The left track's harmonics summed once for both (the same bits).
  Eigen::Vector2d bothTracks(double s) const override;
  std::vector<double> kinks(double, double) const override { return {}; }

 private:
  Iso8608Settings s_;
  std::vector<double> wavenumber_, amplitude_, phase_[2];
};

// A measured profile: heights of both tracks at increasing distances s,
// linearly interpolated, held at the ends; distances are shifted so the
// first sample is at s = 0. Throws std::invalid_argument for fewer than two
// samples, distances not increasing or values not finite.
class MeasuredProfile : public TrackProfile {
 public:
  MeasuredProfile(std::vector<double> s, std::vector<double> left, std::vector<double> right);
  double height(int track, double s) const override;
  std::vector<double> kinks(double s0, double s1) const override;
  double length() const { return s_.back(); }

 private:
  std::vector<double> s_, h_[2];
};
// Reads CSV `s,left,right` (m); throws CsvError naming the file and line.
std::shared_ptr<const MeasuredProfile> readMeasuredProfileCsv(const std::string& path);

// A profile driven at `speed` m/s: contact c sees track contacts[c].first at
// distance V t - contacts[c].second (a rear wheel lags by the wheelbase).
class DrivenProfileRoad : public ContactRoad {
 public:
  DrivenProfileRoad(std::shared_ptr<const TrackProfile> profile, double speed,
                    std::vector<std::pair<int, double>> contacts);
  int contactCount() const override { return static_cast<int>(contacts_.size()); }
  void heights(double t, Eigen::Ref<Eigen::VectorXd> out) const override;
  std::vector<double> breakpoints(double t0, double t1) const override;

 private:
  std::shared_ptr<const TrackProfile> profile_;
  double speed_;
  std::vector<std::pair<int, double>> contacts_;
};

}  // namespace pc_ekf
