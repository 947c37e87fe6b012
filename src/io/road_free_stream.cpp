#include "pc_ekf/io/road_free_stream.h"
#include "pc_ekf/filter/moving_horizon.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/model/model_type.h"

namespace pc_ekf {

std::vector<std::string> RoadFreeStream::inputsFor(const EstimatorConfig& c,
                                                   const MeasurementSeries* record) {
  return inputsFor(c, [record](int ch) {
    return !record || std::any_of(record->begin(), record->end(), [&](const Measurement& m) {
      return std::find(m.channels.begin(), m.channels.end(), ch) != m.channels.end();
    });
  });
}

std::vector<std::string> RoadFreeStream::inputsFor(const EstimatorConfig& c,
                                                   const std::function<bool(int)>& read) {
  const ModelType::RoadFreeInputs wanted = c.model_type->roadFreeInputs();
  const std::vector<int> selected = channelIndices(c);
  std::vector<std::string> names = wanted.required;
  for (const std::string& o : wanted.optional) {
    const int ch = c.model_type->description().channelIndex(o);
    if (std::find(selected.begin(), selected.end(), ch) == selected.end()) continue;
    const bool motion = std::find(wanted.zero_until_read.begin(), wanted.zero_until_read.end(),
                                  o) != wanted.zero_until_read.end();
    if (motion || read(ch)) names.push_back(o);
  }
  return names;
}

std::string RoadFreeStream::unreadMotionWarning(const EstimatorConfig& c,
                                                const std::function<bool(int)>& read) {
  const std::vector<int> selected = channelIndices(c);
  std::string unread;
  for (const std::string& o : c.model_type->roadFreeInputs().zero_until_read) {
    const int ch = c.model_type->description().channelIndex(o);
    if (std::find(selected.begin(), selected.end(), ch) == selected.end() || read(ch)) continue;
    unread += (unread.empty() ? "'" : ", '") + o + "'";
  }
  if (unread.empty()) return "";
  return "measurement.channels selects " + unread +
         ", which the record never reads: taken as 0 throughout (no lateral acceleration: "
         "a turn is not explained and is flagged)";
}

namespace {

// Inputs by kind: travels (u...) and rates (v...).
std::vector<int> inputsStarting(const std::vector<std::string>& inputs, char first) {
  std::vector<int> out;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    if (!inputs[i].empty() && inputs[i][0] == first) out.push_back(static_cast<int>(i));
  }
  return out;
}

// The places in `inputs` of the model's zero_until_read inputs.
std::vector<int> motionPlaces(const ModelType& type, const std::vector<std::string>& inputs) {
  std::vector<int> places;
  for (const std::string& name : type.roadFreeInputs().zero_until_read) {
    const auto at = std::find(inputs.begin(), inputs.end(), name);
    if (at != inputs.end()) places.push_back(static_cast<int>(at - inputs.begin()));
  }
  return places;
}

// Those not read yet (`read`, per place) set to 0 in `in`; returns the
// flags after this sample (kept by the caller only if it is taken).
std::vector<bool> zeroUnreadMotion(const std::vector<int>& places, const std::vector<bool>& read,
                                   std::vector<double>* in) {
  std::vector<bool> now = read;
  for (std::size_t i = 0; i < places.size(); ++i) {
    double& v = (*in)[static_cast<std::size_t>(places[i])];
    if (std::isfinite(v)) {
      now[i] = true;
    } else if (!read[i]) {
      v = 0.0;
    }
  }
  return now;
}

}  // namespace

RoadFreeStream::RoadFreeStream(const EstimatorConfig& c, std::vector<std::string> inputs,
                               double interval)
    : source_(c.source),
      standstill_(0.0, {}, {}, {}, {}) {
  const ModelType& type = *c.model_type;
  for (const std::string& name : inputs) {
    input_channels_.push_back(type.description().channelIndex(name));
  }
  inputs_ = std::make_shared<ReadingInputs>(inputs);
  // The one-step filter at the mean carries the roll angle's error (the
  // gyro's integrated noise) as a state of its own (moving_horizon.h).
  inputs_->setIntegralInState(c.safeguards.horizon.window > 0.0 &&
                              MovingHorizon::carriesRollAngle(type.description().channelNames()));
  try {
    model_ = type.buildRoadFree(*c.modelParameters(), inputs_, c.measurement.zero);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(c.source + ": key 'road.source': " + e.what());
  }
  const auto& channels = type.channelNames();
  for (int ch : channelIndices(c)) {
    if (model_->channelIsInput(ch)) continue;
    if (!model_->channelModelled(ch)) {
      throw ConfigError(c.source + ": key 'measurement.channels': road-free model " + type.name() +
                        " cannot predict '" + channels[static_cast<std::size_t>(ch)] +
                        "' from its inputs (" + std::to_string(inputs.size()) + " readings)");
    }
    outputs_.push_back(ch);
  }
  if (outputs_.empty()) {
    throw ConfigError(c.source + ": key 'measurement.channels': road.source none needs an IMU "
                      "channel to predict (the suspension readings are its inputs)");
  }
  // Each input's noise by the config's rule: an absolute and a relative part.
  const NoiseModel& noise = c.measurement.noise;
  noise_ = noise;
  absolute_.resize(static_cast<Eigen::Index>(inputs.size()));
  relative_.resize(absolute_.size());
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const int ch = input_channels_[i];
    const auto e = static_cast<Eigen::Index>(i);
    relative_[e] = noise.channel_relative.size() != 0 ? noise.channel_relative[ch] : noise.r_relative;
    absolute_[e] = noise.rule == NoiseRule::kSensor ? noise.channel_std[ch] : std::sqrt(noise.r_floor);
  }
  raw_absolute_ = absolute_;
  raw_relative_ = relative_;
  travel_inputs_ = inputsStarting(inputs, 'u');
  rate_inputs_ = inputsStarting(inputs, 'v');
  standstill_ = Standstill(c.measurement.standstill, travel_inputs_, rate_inputs_,
                           std::vector<double>(absolute_.data(), absolute_.data() + absolute_.size()),
                           std::vector<double>(relative_.data(), relative_.data() + relative_.size()));
  // Travel u blended with its rate v (the same suffix: u1/v1, u_fl/v_fl).
  blend_ = c.measurement.travel_blend;
  for (std::size_t i = 0; blend_ > 0.0 && i < inputs.size(); ++i) {
    if (inputs[i].empty() || inputs[i][0] != 'u') continue;
    const auto v = std::find(inputs.begin(), inputs.end(), "v" + inputs[i].substr(1));
    if (v == inputs.end()) continue;
    Blend b;
    b.u = static_cast<int>(i);
    b.v = static_cast<int>(v - inputs.begin());
    blends_.push_back(b);
  }
  // A given interval (a synthetic drive's) from the start; a record's from
  // its stamps (observeInterval): until two samples are read, none, and the
  // blended travel is its reading (the blend starts from it).
  if (interval > 0.0 && !blends_.empty()) {
    interval_ = interval;
    blendNoiseAt(interval);
  }
  observe_interval_ = !(interval > 0.0) && !blends_.empty();
  accel_z_ = type.description().channelIndex("accel_z");
  zero_until_read_ = motionPlaces(type, inputs);
  motion_read_.assign(zero_until_read_.size(), false);
  const auto yaw = std::find(inputs.begin(), inputs.end(), "gyro_z");
  if (yaw != inputs.end()) yaw_ = static_cast<int>(yaw - inputs.begin());
  if (c.safeguards.horizon.window > 0.0 && c.safeguards.horizon.input_noise_states) {
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      if (std::find(outputs_.begin(), outputs_.end(), input_channels_[i]) == outputs_.end()) {
        state_inputs_.push_back(static_cast<int>(i));
      }
    }
  }
}

void RoadFreeStream::blendNoiseAt(double dt) {
  for (Blend& b : blends_) {
    // The blended travel's noise at the sample interval dt, a = tau / (tau + dt):
    // the travel's, low-passed, (1 - a) / (1 + a) of its variance; the rate's
    // trapezoid increments (variance dt^2 sigma_v^2 / 2), high-passed,
    // a^2 / (1 - a^2) of theirs.
    const double a = blend_ / (blend_ + dt);
    const double low = (1.0 - a) / (1.0 + a);
    const double high = a * a / (1.0 - a * a) * dt * dt * 0.5 * absolute_[b.v] * absolute_[b.v];
    absolute_[b.u] = std::sqrt(low * raw_absolute_[b.u] * raw_absolute_[b.u] + high);
    relative_[b.u] = raw_relative_[b.u] * std::sqrt(low);
    // Its noise is low-passed, so consecutive samples share it: lag-1
    // correlation a, plus the rate's trapezoid that both samples hold.
    const double shared = 0.25 * a * a * dt * dt * absolute_[b.v] * absolute_[b.v];
    b.rho = std::min(0.999, a + shared / (absolute_[b.u] * absolute_[b.u]));
    inputs_->setNoiseCorrelation(b.u, b.rho);
  }
}

void RoadFreeStream::observeInterval(double t) {
  // The median of the intervals between the first kIntervalSamples samples,
  // taken anew at 2, 4, 8, ... samples (when the inherited noise is renewed)
  // and kept from the last of them on: a late or dropped sample among them
  // does not move it.
  if (!observe_interval_) return;
  if (std::isfinite(last_time_) && t > last_time_) intervals_.push_back(t - last_time_);
  last_time_ = t;
  if (intervals_.empty() || (samples_ & (samples_ - 1)) != 0) return;
  std::vector<double> sorted = intervals_;
  const std::size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  double median = sorted[mid];
  if (sorted.size() % 2 == 0) {
    const auto lower_end = sorted.begin() + static_cast<std::ptrdiff_t>(mid);
    median = 0.5 * (median + *std::max_element(sorted.begin(), lower_end));
  }
  interval_ = median;
  blendNoiseAt(interval_);
  if (samples_ >= kIntervalSamples) {
    observe_interval_ = false;
    std::vector<double>().swap(intervals_);
  }
}

std::string RoadFreeStream::add(const Measurement& m, Measurement* out) {
  std::vector<double> in(input_channels_.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t j = 0; j < m.channels.size(); ++j) {
    const auto it = std::find(input_channels_.begin(), input_channels_.end(), m.channels[j]);
    if (it != input_channels_.end()) in[it - input_channels_.begin()] = m.values[static_cast<Eigen::Index>(j)];
  }
  // The vehicle's horizontal motion not read yet: 0 (ReadingInputs holds
  // the last reading once there is one).
  std::vector<bool> motion_read = zeroUnreadMotion(zero_until_read_, motion_read_, &in);
  // A stop: the travels their means since it began, the rates 0; the blend
  // holds the mean. The blends' and the stop's next state, kept only if the
  // sample is taken (the scratch's capacity is reused).
  raw_ = in;
  const Standstill::Decision still = standstill_.decide(m.time, raw_);
  standstill_.apply(still, raw_, &in);
  blend_next_ = blends_;
  for (Blend& b : blend_next_) {
    if (!still.standing) {
      blendTravel(b, m.time, &in);
      continue;
    }
    b.started = true;
    b.u_blended = in[static_cast<std::size_t>(b.u)];
    b.t_last = m.time;
    b.v_last = 0.0;
  }
  // The yaw rate shrunk by its spread so far (yaw_ above); kept if taken.
  double yaw_square = yaw_square_, yaw_time = yaw_time_, yaw_shrink = yaw_shrink_;
  if (yaw_ >= 0 && std::isfinite(in[static_cast<std::size_t>(yaw_)])) {
    double& r = in[static_cast<std::size_t>(yaw_)];
    if (!std::isfinite(yaw_square_) || !(m.time > yaw_time_)) {
      yaw_square = r * r;
    } else {
      const double a = std::exp(-(m.time - yaw_time_) / kYawWindow);
      yaw_square = a * yaw_square_ + (1.0 - a) * r * r;
    }
    yaw_time = m.time;
    const double sigma = std::hypot(raw_absolute_[yaw_], raw_relative_[yaw_] * r);
    yaw_shrink = yaw_square > 0.0 ? std::max(0.0, 1.0 - sigma * sigma / yaw_square) : 0.0;
    r *= yaw_shrink;
  }
  const std::string problem = inputs_->append(m.time, in.data());
  if (!problem.empty()) return problem;
  if (yaw_ >= 0) {
    yaw_square_ = yaw_square;
    yaw_time_ = yaw_time;
    yaw_shrink_before_ = samples_ > 0 ? yaw_shrink_ : 1.0;
    yaw_shrink_ = yaw_shrink;
  }
  blends_.swap(blend_next_);
  motion_read_.swap(motion_read);
  standstill_.commit(m.time, raw_, still);
  ++samples_;
  observeInterval(m.time);
  Measurement o = onlyChannels(m, outputs_);
  o.standing = still.standing;
  for (std::size_t j = 0; j < o.channels.size(); ++j) {
    if (o.channels[j] != accel_z_) continue;
    accel_z_sum_ += o.values[static_cast<Eigen::Index>(j)];
    ++accel_z_count_;
  }
  // The sample's own inherited variance; the load it is weighed at (tare)
  // renewed from the samples so far at 1, 2, 4, ... samples.
  if ((samples_ & (samples_ - 1)) == 0) updateInputNoise();
  const auto k = static_cast<std::size_t>(samples_ - 1);
  if (!state_inputs_.empty()) {
    Eigen::MatrixXd slopes;
    inputSlopes(k, still, &o, serial_ ? &slopes : nullptr);
    if (serial_) reckonSerialNoise(slopes, &o);
  } else if (yaw_ >= 0 || serial_) {
    Eigen::MatrixXd covariance, slopes;
    inheritedWithSlopes(k, still, &covariance, &slopes);
    if (yaw_ >= 0) shrinkYawNoise(&covariance, &slopes);
    o.extra_covariance = covariance(o.channels, o.channels);
    if (serial_) reckonSerialNoise(slopes, &o);
  } else if (still.standing) {
    if (!travels_at_) updateInputNoise();
    const Eigen::MatrixXd standing =
        travels_at_(k, nullptr) / static_cast<double>(still.averaged) + others_at_(k, nullptr);
    o.extra_covariance = standing(o.channels, o.channels);
  } else {
    o.extra_covariance = inherited_at_(k, nullptr)(o.channels, o.channels);
  }
  *out = std::move(o);
  return "";
}

void RoadFreeStream::inheritedWithSlopes(std::size_t k, const Standstill::Decision& still,
                                         Eigen::MatrixXd* covariance, Eigen::MatrixXd* slopes) {
  if (!still.standing) {
    *covariance = inherited_at_(k, slopes);
    return;
  }
  if (!travels_at_) updateInputNoise();
  Eigen::MatrixXd travel_slopes, other_slopes;
  const double count = static_cast<double>(still.averaged);
  *covariance = travels_at_(k, &travel_slopes) / count + others_at_(k, &other_slopes);
  *slopes = travel_slopes / std::sqrt(count) + other_slopes;
}

void RoadFreeStream::inputSlopes(std::size_t k, const Standstill::Decision& still, Measurement* o,
                                 Eigen::MatrixXd* all_slopes) {
  // Each input's noise at this sample against that at the one before: a
  // stop's travel is the mean of the readings since it began, N of them,
  // whose mean over N - 1 it shares by sqrt((N - 1) / N); a blended travel's
  // is low-passed (its blend's rho); a stop's start or end, or anything
  // else, independent. The inherited covariance takes the same.
  const Eigen::Index n = static_cast<Eigen::Index>(input_channels_.size());
  Eigen::VectorXd rho = Eigen::VectorXd::Zero(n);
  for (int i : travel_inputs_) {
    if (still.standing && was_standing_ && still.averaged > 1) {
      const double count = static_cast<double>(still.averaged);
      rho[i] = std::sqrt((count - 1.0) / count);
    }
  }
  for (const Blend& b : blends_) {
    if (!still.standing && !was_standing_) rho[b.u] = b.rho;
  }
  for (int i : travel_inputs_) inputs_->setNoiseCorrelation(i, rho[i]);
  was_standing_ = still.standing;
  Eigen::MatrixXd covariance, slopes;
  inheritedWithSlopes(k, still, &covariance, &slopes);
  if (yaw_ >= 0) shrinkYawNoise(&covariance, &slopes);
  // The inputs not carried (the gyro) stay in the covariance alone.
  Eigen::MatrixXd carried = Eigen::MatrixXd::Zero(slopes.rows(), slopes.cols());
  for (int i : state_inputs_) {
    carried.col(i) = slopes.col(i);
    carried.col(n + i) = slopes.col(n + i);
  }
  o->extra_covariance = covariance(o->channels, o->channels);
  o->input_slopes = carried(o->channels, Eigen::all);
  o->input_correlation = rho;
  if (all_slopes) *all_slopes = std::move(slopes);
}

void RoadFreeStream::reckonSerialNoise(const Eigen::MatrixXd& slopes, Measurement* o) {
  const Eigen::Index n = static_cast<Eigen::Index>(input_channels_.size());
  const Eigen::Index c = static_cast<Eigen::Index>(o->channels.size());
  if (c == 0 || slopes.cols() != 2 * n) return;
  // r = A eps_k - B eps_{k-1}: A the output's own noise where it is an input
  // (a gyro) less the slopes now, B the slopes before; whitened as the
  // residuals are (whitenedResiduals: scaled, then decorrelated).
  Eigen::MatrixXd a = -slopes(o->channels, Eigen::seqN(0, n));
  Eigen::MatrixXd b = slopes(o->channels, Eigen::seqN(n, n));
  Eigen::VectorXd rho(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    rho[i] = inputs_->noiseCorrelation(static_cast<int>(i));
    for (Eigen::Index r = 0; r < c; ++r) {
      if (o->channels[static_cast<std::size_t>(r)] != input_channels_[static_cast<std::size_t>(i)]) continue;
      a(r, i) += std::hypot(raw_absolute_[i], raw_relative_[i] * o->values[r]);
    }
  }
  const NoiseWhitening white(noise_, *o);
  const Eigen::VectorXd scale = white.variances().cwiseSqrt().cwiseInverse();
  a = scale.asDiagonal() * a;
  b = scale.asDiagonal() * b;
  white.whiten(a);
  white.whiten(b);
  o->serial_variance = serial_->add(a, b, rho);
}

void RoadFreeStream::shrinkYawNoise(Eigen::MatrixXd* covariance, Eigen::MatrixXd* slopes) const {
  // The gyro's noise is independent from sample to sample (no lag-1 term):
  // its share is a a' + b b', a and b its slopes at this sample and the one before.
  const Eigen::Index n = static_cast<Eigen::Index>(input_channels_.size());
  const Eigen::VectorXd a = slopes->col(yaw_), b = slopes->col(n + yaw_);
  *covariance += (yaw_shrink_ - 1.0) * a * a.transpose() +
                 (yaw_shrink_before_ - 1.0) * b * b.transpose();
  slopes->col(yaw_) *= std::sqrt(yaw_shrink_);
  slopes->col(n + yaw_) *= std::sqrt(yaw_shrink_before_);
}

void RoadFreeStream::blendTravel(Blend& b, double t, std::vector<double>* in) const {
  double& u = (*in)[static_cast<std::size_t>(b.u)];
  const double v = (*in)[static_cast<std::size_t>(b.v)];
  if (!std::isfinite(u)) return;  // held by the inputs; the blend waits for a reading
  if (!b.started || !std::isfinite(v) || !std::isfinite(b.v_last) || !(t > b.t_last)) {
    b.u_blended = u;  // starts (again) from the reading itself
  } else {
    const double dt = t - b.t_last, a = blend_ / (blend_ + dt);
    b.u_blended = a * (b.u_blended + 0.5 * (b.v_last + v) * dt) + (1.0 - a) * u;
  }
  b.started = true;
  b.t_last = t;
  b.v_last = v;
  u = b.u_blended;
}

void RoadFreeStream::updateInputNoise() {
  const double mean_accel_z = accel_z_count_ > 0 ? accel_z_sum_ / static_cast<double>(accel_z_count_) : 0.0;
  inherited_at_ = model_->inputNoiseBySample(absolute_, relative_, mean_accel_z);
  if (!standstill_.enabled()) return;
  // Standing: each travel's raw noise (its mean's is that over the readings
  // averaged), no rate noise (zero), the other inputs' as they are.
  Eigen::VectorXd travel_abs = Eigen::VectorXd::Zero(absolute_.size()), travel_rel = travel_abs;
  Eigen::VectorXd other_abs = absolute_, other_rel = relative_;
  for (int i : travel_inputs_) {
    travel_abs[i] = raw_absolute_[i];
    travel_rel[i] = raw_relative_[i];
    other_abs[i] = other_rel[i] = 0.0;
  }
  for (int i : rate_inputs_) other_abs[i] = other_rel[i] = 0.0;
  travels_at_ = model_->inputNoiseBySample(travel_abs, travel_rel, mean_accel_z);
  others_at_ = model_->inputNoiseBySample(other_abs, other_rel, mean_accel_z);
}

bool RoadFreeStream::waitingForInputs(const Measurement& m) const {
  if (!inputs_->empty()) return false;
  for (std::size_t i = 0; i < input_channels_.size(); ++i) {
    const int ch = input_channels_[i];
    if (std::find(zero_until_read_.begin(), zero_until_read_.end(), static_cast<int>(i)) !=
        zero_until_read_.end()) {
      continue;  // 0 until read
    }
    const auto it = std::find(m.channels.begin(), m.channels.end(), ch);
    if (it == m.channels.end() || std::isnan(m.values[static_cast<Eigen::Index>(it - m.channels.begin())])) {
      return true;
    }
  }
  return false;
}

std::string droppedWarning(std::size_t dropped, const std::string& first_problem) {
  if (dropped == 0) return "";
  return std::to_string(dropped) + " sample(s) before every road-free input had been "
         "read dropped, as estimator_node drops them (from " + first_problem +
         "); the record goes on from sample " + std::to_string(dropped + 1);
}

std::string roadFreeRefusal(const EstimatorConfig& c, std::size_t k, const Measurement& m,
                            const std::string& problem) {
  return c.source + ": road.source none: sample " + std::to_string(k + 1) + " (t = " +
         std::to_string(m.time) + " s): " + problem;
}

RoadFreeRecord roadFreeRecord(const EstimatorConfig& c, const MeasurementSeries& record,
                              double interval) {
  RoadFreeStream stream(c, RoadFreeStream::inputsFor(c, &record), interval);
  if (c.health.predictive_check) stream.trackSerialNoise();  // the batch methods' check
  RoadFreeRecord r;
  r.outputs.reserve(record.size());
  std::string first_problem;
  const auto where = [&](std::size_t k) {
    return "sample " + std::to_string(k + 1) + " (t = " + std::to_string(record[k].time) + " s)";
  };
  for (std::size_t k = 0; k < record.size(); ++k) {
    Measurement out;
    const bool waiting = std::isfinite(record[k].time) && stream.waitingForInputs(record[k]);
    const std::string problem = stream.add(record[k], &out);
    if (!problem.empty() && waiting) {  // as estimator_node: dropped
      if (r.dropped++ == 0) first_problem = where(k) + ": " + problem;
      continue;
    }
    if (!problem.empty()) throw ConfigError(roadFreeRefusal(c, k, record[k], problem));
    r.outputs.push_back(std::move(out));
  }
  if (r.outputs.empty() && r.dropped > 0) {
    throw ConfigError(c.source + ": road.source none: no sample has every road-free input (" +
                      std::to_string(r.dropped) + " samples; " + first_problem + ")");
  }
  r.warning = droppedWarning(r.dropped, first_problem);
  r.model = stream.model();
  return r;
}

RoadFreeCheck checkRoadFreeRecord(const EstimatorConfig& c, const MeasurementSeries& record) {
  RoadFreeChecker check(c, RoadFreeStream::inputsFor(c, &record));
  for (const Measurement& m : record) check.add(m);
  return check.finish();
}

// The stream refuses what its inputs refuse (the travel blend keeps a
// reading finite): the raw inputs through inputs of their own, forgotten as
// they go.
RoadFreeChecker::RoadFreeChecker(const EstimatorConfig& c, const std::vector<std::string>& inputs)
    : c_(c), inputs_(inputs), in_(inputs.size()), motion_(motionPlaces(*c.model_type, inputs)),
      motion_read_(motion_.size(), false) {
  for (const std::string& name : inputs) {
    channels_.push_back(c.model_type->description().channelIndex(name));
  }
}

void RoadFreeChecker::add(const Measurement& m) {
  if (!refusal_.empty()) return;
  const std::size_t k = k_++;
  std::fill(in_.begin(), in_.end(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t j = 0; j < m.channels.size(); ++j) {
    const auto it = std::find(channels_.begin(), channels_.end(), m.channels[j]);
    if (it == channels_.end()) continue;
    in_[static_cast<std::size_t>(it - channels_.begin())] = m.values[static_cast<Eigen::Index>(j)];
  }
  std::vector<bool> motion_read = zeroUnreadMotion(motion_, motion_read_, &in_);
  const bool waiting = std::isfinite(m.time) && check_.dropped == k &&
                       std::any_of(in_.begin(), in_.end(), [](double v) { return std::isnan(v); });
  const std::string problem = inputs_.append(m.time, in_.data());
  if (!problem.empty() && waiting) {  // as estimator_node and roadFreeRecord: dropped
    if (check_.dropped++ == 0) {
      first_problem_ = "sample 1 (t = " + std::to_string(m.time) + " s): " + problem;
    }
    return;
  }
  if (!problem.empty()) {
    refusal_ = roadFreeRefusal(c_, k, m, problem);
    return;
  }
  motion_read_.swap(motion_read);
  inputs_.forget(m.time, -std::numeric_limits<double>::infinity());
}

RoadFreeCheck RoadFreeChecker::finish() const {
  if (!refusal_.empty()) throw ConfigError(refusal_);
  if (check_.dropped == k_ && check_.dropped > 0) {
    throw ConfigError(c_.source + ": road.source none: no sample has every road-free input (" +
                      std::to_string(check_.dropped) + " samples; " + first_problem_ + ")");
  }
  RoadFreeCheck out = check_;
  out.warning = droppedWarning(check_.dropped, first_problem_);
  return out;
}

std::string roadFreeCaveat(const EstimatorConfig& c) {
  if (c.road.source != RoadSource::kNone || c.model_type->name() != "full_car") return "";
  const auto& ch = c.measurement.channels;
  if (std::find(ch.begin(), ch.end(), "accel_y") == ch.end()) return "";
  return "road-free full car with accel_y: not validated, reported not healthy (the gyros' "
         "drift in accel_y makes the load's lateral position look several times more precise "
         "than it is; leave accel_y out, docs/real_vehicle.md)";
}

}  // namespace pc_ekf
