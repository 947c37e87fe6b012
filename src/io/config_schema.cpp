#include "pc_ekf/io/config_schema.h"

namespace pc_ekf {

// One line per key: path, type, default, domain, meaning.
// test_io_config_schema fails when this table and the parser disagree.
const std::vector<ConfigKey>& configSchema() {
  static const std::vector<ConfigKey> keys = {
      // model and its values
      {"model.type", "text", "roll_plane", "roll_plane, full_car or a plugin's package/Class", "the model type: it owns the `vehicle:` keys, the contacts (road inputs), the channels and the suspensions (`node.joints` keys); [models.md](models.md)"},
      {"vehicle.<name>", "number or choice", "the model type's (models.md)", "the model type's (models.md)", "a value of the model: its parameters, settings and choices, with names, units, defaults and domains in [models.md](models.md); the model's rates are wheel rates; the datasheet forms below convert to them when the section is read ([models.md, datasheet values](models.md#datasheet-values))"},
      {"vehicle.motion_ratio_<side>", "number", "none", "(0, inf)", "datasheet: spring (and damper) travel per wheel travel of a side (`<side>`: a suffix of the model's `spring_linear_` keys: left, right; front, rear); converts the side's `spring_rate_`, `spring_cubic_rate_`, `damper_rate_`, damper table (and the roll plane's `spring_track`); given alone it is refused"},
      {"vehicle.damper_motion_ratio_<side>", "number", "none (motion_ratio_<side>)", "(0, inf)", "datasheet: the damper's travel per wheel travel when it differs from the spring's"},
      {"vehicle.spring_rate_<side>", "number", "none", "(0, inf)", "datasheet: N/m at the spring; `spring_linear_<side>` = rate x ratio^2 (not both)"},
      {"vehicle.spring_cubic_rate_<side>", "number", "none", "[0, inf)", "datasheet: N/m^3 at the spring; `spring_cubic_<side>` = rate x ratio^4 (not both)"},
      {"vehicle.damper_rate_<side>", "number", "none", "[0, inf)", "datasheet: N s/m at the damper; `damping_<side>` = rate x damper ratio^2 (not both, nor with a table)"},
      {"vehicle.damper_table", "map", "none", "bump: and rebound: lists", "datasheet (roll plane): the measured damper curve at the damper, for both sides; sets `damper: table`; at the wheel velocity / ratio and force x ratio; `damping_<side>` defaults to the curve's mean bump and rebound slope at 0 and scales the curve by damping / that slope ([models.md](models.md#datasheet-values))"},
      {"vehicle.damper_table.bump", "list", "required", "[velocity m/s, force N] pairs, >= 0, velocity increasing, force not falling", "compression: the force magnitude at each velocity magnitude; (0, 0) is added (a point at velocity 0 must have force 0); linear between the points, extrapolated along the last segment"},
      {"vehicle.damper_table.rebound", "list", "required", "as bump", "extension, as bump"},
      {"vehicle.damper_table_<side>", "map", "none", "as damper_table (not with it)", "datasheet (roll plane): one side's curve, keys as `damper_table`"},
      {"vehicle.wheel_track", "number", "none", "(0, inf)", "datasheet (roll plane): the track at the wheels; `bar_length` (the wheel track: the model's rates act at the wheels) takes it; not with bar_length or spring_track"},
      {"vehicle.spring_track", "number", "none", "(0, inf)", "datasheet (roll plane): the track at the springs; bar_length = spring_track / the mean of motion_ratio_left and motion_ratio_right (arms pivoting near the centre line: prefer wheel_track)"},
      {"vehicle.wheelbase", "number", "none", "(0, inf)", "datasheet (full car): with front_axle_load_share, front_axle_distance a = (1 - share) x wheelbase and rear_axle_distance b = share x wheelbase (not with them)"},
      {"vehicle.front_axle_load_share", "number", "none", "(0, 1)", "datasheet (full car): the share of the body's own weight on the front axle (axle loads less the unsprung masses, over their sum)"},
      // what is estimated
      {"uncertain", "list", "[] (needs tolerances:)", "at least one entry, or tolerances: with a positive one", "the parameters to estimate (the load): value = nominal (1 + relative_range xi); a config with neither `uncertain:` entries nor a positive `tolerances:` entry is refused"},
      {"uncertain[i].name", "text", "required", "a model parameter, each once", "the `vehicle:` key estimated"},
      {"uncertain[i].nominal", "number", "the vehicle value", "any", "nominal value"},
      {"uncertain[i].relative_range", "number", "required", "(0, inf)", "relative half-width of the prior"},
      {"uncertain[i].germ.family", "choice", "beta", "beta, uniform, gaussian or gamma", "the germ's distribution: beta (shapes alpha, beta on [-1, 1]), uniform on [-1, 1], gaussian, gamma (alpha = shape)"},
      {"uncertain[i].germ.alpha", "number", "2", "(0, inf)", "beta and gamma: first shape"},
      {"uncertain[i].germ.beta", "number", "2", "(0, inf)", "beta: second shape"},
      {"tolerances", "map", "{}", "model parameters, not under uncertain:", "vehicle values known to a relative tolerance, estimated too (nuisance parameters, after the `uncertain:` entries in the model's parameter order); [real_vehicle.md](real_vehicle.md)"},
      {"tolerances.<name>", "number or map", "none", "[0, inf)", "a number: the relative half-range with a Beta(2, 2) germ, value = vehicle value (1 + t xi); 0 = fixed; a map: the keys below"},
      {"tolerances.<name>.nominal", "number", "the vehicle value", "any, not 0", "nominal value"},
      {"tolerances.<name>.relative_range", "number", "0", "[0, inf)", "relative half-width; 0 = fixed"},
      {"tolerances.<name>.germ.family", "choice", "beta", "as uncertain[i].germ", "as `uncertain[i].germ.family`"},
      {"tolerances.<name>.germ.alpha", "number", "2", "(0, inf)", "as `uncertain[i].germ.alpha`"},
      {"tolerances.<name>.germ.beta", "number", "2", "(0, inf)", "as `uncertain[i].germ.beta`"},
      {"tolerances_prune", "number", "0", "[0, 1]", "fix (at their nominal) the tolerances whose largest total Sobol index on the observed channels (whole-record runs of the prior, docs/method.md §3.7) is below this, before the run; 0 = off; the node applies it only on an analytic road"},
      {"vehicle_file", "text", "none", "a file path", "a vehicle file (`calibrate_vehicle`'s output), relative to the config: its `vehicle:` keys and `tolerances:` entries replace the config's; it holds only those two sections"},
      // polynomial chaos and its design
      {"pc.order", "integer", "4", "[0, 20]", "total degree p; S = C(n + p, p) basis terms (15 for n = 2)"},
      {"pc.truncation", "choice", "total_degree", "total_degree or hyperbolic", "hyperbolic: only the multi-indices with q-norm (sum_i alpha_i^q)^(1/q) <= p (fewer interactions)"},
      {"pc.q_norm", "number", "1 (hyperbolic: 0.5)", "(0, 1]", "hyperbolic only (refused otherwise); 1 = total degree"},
      {"pc.tolerance_interactions", "bool", "true", "true or false", "false: a basis term holds at most one `tolerances:` germ (a tolerance interacts with the `uncertain:` parameters, not with another tolerance; n = 16, p = 2: S 153 -> 62)"},
      {"pc.batch_tolerance_interactions", "bool", "the one-step filter's (pc.tolerance_interactions)", "true or false", "the batch methods' basis (es_mda, whole_set, the node's `~estimate_batch`): true keeps the tolerances' products with each other there while the one-step filter goes without (ES-MDA's passes evaluate the surrogate over the prior's whole width: [performance.md](performance.md))"},
      {"collocation.sequence", "choice", "auto", "auto, halton, scrambled_halton, hammersley, gauss or smolyak", "the collocation points; auto: gauss with pc.order + 1 nodes per germ when those (p + 1)^n nodes are at most the default 30 points (n = 2, p = 4: 5 x 5; n = 3: p <= 2) and none of `points`, `batch_points`, `start_index`, `seed` is given; otherwise halton up to 12 uncertain parameters, scrambled_halton above; gauss: tensor Gauss rule (`points` nodes per germ, refused above 20 000 nodes)"},
      {"collocation.points", "integer", "the sequence's: 30 (auto's gauss: pc.order + 1)", "[1, 1000000] (Q >= S)", "Q, the number of points (gauss: per germ; not used by smolyak); given with sequence auto, the Halton design's Q (auto then takes halton or scrambled_halton)"},
      {"collocation.batch_points", "integer", "the one-step filter's (collocation.points)", "[1, 1000000] (Q >= the batch basis's S)", "the batch methods' Q (es_mda, whole_set, the node's `~estimate_batch`); the one-step filter uses `points`"},
      {"collocation.level", "integer", "-1 (= pc.order)", "[0, 30]", "smolyak: sparse grid of the germs' Gauss rules, exact to total degree 2 level + 1"},
      {"collocation.projection", "choice", "auto", "auto, regression or quadrature", "auto: quadrature for gauss, least squares otherwise (also smolyak, whose negative weights make repeated quadrature projections unstable); quadrature needs gauss or smolyak"},
      {"collocation.nested", "bool", "false", "true or false (true: smolyak only)", "smolyak: nested Clenshaw-Curtis rules for uniform and symmetric Beta germs (same exactness, shared nodes)"},
      {"collocation.start_index", "unsigned", "1", "[0, 2^64)", "Halton index of the first point (also scrambled_halton)"},
      {"collocation.seed", "unsigned", "1", "[0, 2^64)", "scrambled_halton: seed of the digit permutations; also seeds the scrambled Halton points of the sensitivity (`--sensitivity`, the node's start sensitivity, `tolerances_prune`), whatever the sequence"},
      {"collocation.max_condition", "number", "1e+08", "[1, inf)", "refuse a worse-conditioned design"},
      {"collocation.threads", "integer", "0", "[0, 1024]", "forecast threads, 0 = the machine's cores (results identical for any count; designs under 48 points stay on one thread); also the sensitivity's simulation threads"},
      {"collocation.loo_warning", "number", "0.1", "[0, inf)", "relative leave-one-out error of the projection above which a sample is flagged (warning only)"},
      // the road
      {"road.source", "choice", "speed_bump", "speed_bump, sine, series, topic, course, iso8608, profile or none", "where the road comes from; topic: the node's `road/profile` or `road/heights`; none: no road known (road-free estimation, [method.md §4.10](method.md#410-road-free-estimation-roadsource-none); estimator_node too, without a checkpoint)"},
      {"road.speed_kmh", "number", "36", "(0, 1000]", "iso8608 and profile: the driving speed, km/h"},
      {"road.iso8608.class", "choice", "B", "A, B, C, D or E", "ISO 8608 class: Gd(0.1 cycles/m) = 16, 64, 256, 1024, 4096 x 10^-6 m^3"},
      {"road.iso8608.seed", "unsigned", "1", "[0, 2^64)", "phases of the sum of sinusoids"},
      {"road.iso8608.correlation", "number", "0", "[0, 1]", "right = c left + sqrt(1 - c^2) independent"},
      {"road.iso8608.lead_in", "number", "2", "[0, 1e+06]", "m faded in from level ground"},
      {"road.iso8608.n_min", "number", "0.02", "(0, 1000]", "lowest spatial frequency, cycles/m"},
      {"road.iso8608.n_max", "number", "5", "(0.02, 1000] (above n_min)", "highest spatial frequency, cycles/m"},
      {"road.iso8608.bands", "integer", "200", "[1, 100000]", "log-spaced bands of the sum of sinusoids"},
      {"road.profile.file", "text", "\"\"", "a CSV path (required by source profile)", "measured profile CSV `s,left,right` (m); a full car's rear wheels follow a wheelbase later"},
      {"road.speed_bump.speed_kmh", "number", "16", "(0, inf)", "km/h over the bump"},
      {"road.speed_bump.height_left", "number", "0.1", "any", "m, tyre 1's bump"},
      {"road.speed_bump.height_right", "number", "0.08", "any", "m, tyre 2's bump"},
      {"road.speed_bump.ramp_up_length", "number", "1", "(0, inf)", "m of travel"},
      {"road.speed_bump.flat_length", "number", "1", "[0, inf)", "m of travel"},
      {"road.speed_bump.ramp_down_length", "number", "1", "(0, inf)", "m of travel"},
      {"road.speed_bump.delay_fraction", "number", "0.2", "[0, inf)", "tyre 2's delay, as a fraction of the bump length"},
      {"road.speed_bump.start_distance", "number", "0", "[0, inf)", "m of travel before the bump"},
      {"road.sine.amplitude", "number", "0.05", "any", "m"},
      {"road.sine.frequency", "number", "1", "(0, inf)", "Hz"},
      {"road.sine.right_sign", "number", "-1", "[-1, 1]", "y2 = right_sign y1"},
      {"road.series.file", "text", "\"\"", "a CSV path (required by source series)", "road CSV `t,y1,y2` (full car: `t,front_left,front_right,rear_left,rear_right`)"},
      {"road.course", "list", "[] (required by source course)", "segments", "source course: segments played one after another, each from its own t = 0; rest holds the road where the segment before it left it (a stop), an iso8608 segment starts from there too; the road stays where the last segment left it; boundaries are integrator breakpoints; the full car's rear wheels follow the front ones a wheelbase behind, by distance driven; see `load_change_course.yaml` and `long_drive.yaml`, [method.md §1.5](method.md#15-road-inputs)"},
      {"road.course[i].type", "choice", "required", "speed_bump, sine, rest, iso8608, turn, lane_change, slalom, brake or accelerate", "speed_bump lasts until both tyres are past the bump; sine starts at phase 0 and steps back where it ends; rest is the vehicle standing still (the heights where the segment before it ended: 0 unless an iso8608 segment came before); iso8608 is the ISO 8608 road driven at speed_kmh, blended over road.iso8608.lead_in from the heights it starts at (then the standalone road's heights), and leaves the heights where it ends; turn, lane_change and slalom are lateral manoeuvres driven at speed_kmh on the `surface` (the lateral acceleration a known input of the model, [models.md](models.md)); brake and accelerate are straight, the speed falling or rising from speed_kmh at a constant rate (a_x = dV/dt, a known input too)"},
      {"road.course[i].duration", "number", "required (all but speed_bump)", "(0, inf)", "s, every segment but speed_bump; lane_change: one period of its sine"},
      {"road.course[i].speed_kmh", "number", "the road.speed_bump.speed_kmh or road.speed_kmh value", "(0, inf) (iso8608 and manoeuvres: (0, 1000])", "km/h: over the bump (speed_bump segment), or the driving speed (iso8608 segment and manoeuvres)"},
      {"road.course[i].lateral_acceleration", "number", "3", "any", "m/s^2, left positive: a turn's steady a_y, a lane_change's and a slalom's peak (turn, lane_change, slalom)"},
      {"road.course[i].deceleration", "number", "3", "(0, inf)", "brake: m/s^2, the speed falls at this rate from speed_kmh (it must not reach 0 before the segment ends)"},
      {"road.course[i].acceleration", "number", "3", "(0, inf)", "accelerate: m/s^2, the speed rises at this rate from speed_kmh (which may be 0 here)"},
      {"road.course[i].radius", "number", "0", "any", "turn: m, left positive; not 0: a_y = V^2 / radius instead of lateral_acceleration"},
      {"road.course[i].ramp", "number", "1", "[0, inf)", "turn: s over which a_y is reached and left (half-cosines; at most half the turn)"},
      {"road.course[i].frequency", "number", "0.5", "(0, inf)", "slalom: Hz, a_y = lateral_acceleration sin(2 pi frequency t)"},
      {"road.course[i].surface", "choice", "flat", "flat, iso8608 or profile", "turn, lane_change, slalom, brake, accelerate: the road under the manoeuvre: flat (the heights where the segment before left it), the ISO 8608 road of class, seed and correlation (as an iso8608 segment), or a measured profile (`file`, from `start` m into it, shifted to start at the heights where the segment before left them; it leaves the heights where it ends)"},
      {"road.course[i].file", "text", "the road.profile.file value", "a CSV path s,left,right (m)", "surface profile: the measured profile under the manoeuvre (as road.profile.file)"},
      {"road.course[i].start", "number", "0", "[0, inf)", "surface profile: m into the profile where the segment starts"},
      {"road.course[i].class", "choice", "the road.iso8608.class value", "A, B, C, D or E", "iso8608 segment (and a manoeuvre on surface iso8608): its ISO 8608 class"},
      {"road.course[i].seed", "unsigned", "the road.iso8608.seed value + i", "[0, 2^64)", "iso8608 segment: the phases' seed; by default the road's seed plus the segment's index in the course (mod 2^64), so segments are not copies of each other (course[0] is the iso8608 road of that seed)"},
      {"road.course[i].correlation", "number", "the road.iso8608.correlation value", "[0, 1]", "iso8608 segment: right = c left + sqrt(1 - c^2) independent (its other keys: road.iso8608's)"},
      {"road.course[i].<speed_bump or sine key>", "number", "the road.speed_bump or road.sine value", "as there", "a `road.speed_bump` key (speed_bump segment) or a `road.sine` key (sine segment)"},
      // samples and measurements
      {"sampling.samples", "integer", "10", "[1, 100000000]", "N; t_k = k duration / N, k = 1..N"},
      {"sampling.duration", "number", "3", "(0, inf)", "s"},
      {"measurement.channels", "names", "[u1, u2, v1, v2] (the model's suspension channels)", "distinct channels of the model", "observed channels; the IMU channels (`accel_y`, `accel_z`, `gyro_x`; full car also `gyro_y`) only when named"},
      {"measurement.travel_blend", "number", "0", "[0, 10]", "s; road-free only: each travel reading (u) blended with the integral of its rate (v) by a complementary filter of this time constant, which cuts the travel's noise that would otherwise make the springs look soft; 0 = the raw readings; [method.md §4.10](method.md#410-road-free-estimation-roadsource-none)"},
      {"measurement.standstill", "number", "0", "[0, 60]", "s; road-free only: a stop is recognised when over this window every suspension rate's RMS and every travel's spread stay below 1.5 times their noise std, and ends at a reading beyond 5 std; while standing each travel is its mean since the stop began and each rate 0, so that the sensors' noise is not read as motion the IMU does not see; 0 = never; [method.md §4.10](method.md#410-road-free-estimation-roadsource-none)"},
      {"measurement.zero", "choice", "rest", "rest or tare", "rest: every channel a deviation from the loaded vehicle at rest (the paper's); tare: as the sensors give them, suspension zeroed on the empty vehicle and the IMU raw (+g on `accel_z` at rest); [method.md §1.6](method.md#16-measurements-and-synthetic-data)"},
      {"measurement.noise_relative", "number or numbers", "0.01", "[0, inf)", "synthetic data noise: std = noise_relative \\|z_true\\|; one number, or one per channel of `channels` (or of the model)"},
      {"measurement.noise_floor", "number", "0", "[0, inf)", "synthetic data: plus this absolute std (in quadrature)"},
      {"measurement.r_rule", "choice", "paper", "paper or sensor", "filter R: paper: R_jj = max(r_floor, (r_relative z_obs)^2); sensor: R_jj = sensor_std_c^2 + (r_relative z_obs)^2 ([reliability.md](reliability.md#r-for-real-sensors))"},
      {"measurement.r_relative", "number or numbers", "0.01", "[0, inf)", "one number, or one per channel of `channels` (or of the model)"},
      {"measurement.r_floor", "number", "1e-12", "(0, inf)", "paper rule only"},
      {"measurement.sensor_std", "numbers", "[] (required by r_rule sensor)", "positive, one per channel of `channels` or of the model, or one for all", "sensor rule: absolute std per channel (m, m/s, m/s^2, rad/s), from the datasheet"},
      // the synthetic truth
      {"truth.xi", "numbers", "[0, 0] (zeros: one per uncertain: entry)", "one per uncertain: entry (or per estimated parameter), in the germs' support", "the true germ coordinates; the paper cases set [0.2326, -0.3875] (M = 223.26 kg, d_CG = 0.6882 m)"},
      {"truth.seed", "unsigned", "1", "[0, 2^64)", "measurement-noise seed (`estimate_offline --seed` overrides)"},
      {"truth.vehicle.<name>", "number or choice", "the vehicle: value", "as vehicle.<name>, not an uncertain: name", "a `vehicle:` value for the simulated truth only (same names and checks), e.g. `truth: {vehicle: {spring_linear_left: 20325.06}}`; an uncertain parameter's truth comes from truth.xi"},
      {"truth.road", "map", "unset (the config's road)", "a road: section, not topic or none", "the road the truth drives (e.g. a rough road the estimator is not told); needed for synthetic data when `road.source` is none"},
      {"truth.sensor.noise_floor", "number or numbers", "[]", "[0, inf)", "per channel of `channels` or of the model, or one for all: absolute std; given, it replaces `measurement.noise_floor`"},
      {"truth.sensor.bias", "number or numbers", "[]", "any", "constant offset added to the reading"},
      {"truth.sensor.quantisation", "number or numbers", "[]", "[0, inf)", "step: the reading rounded to a multiple after noise and bias; 0 = off"},
      {"truth.timing.jitter", "number", "0", "[0, inf)", "s, std of the true sampling instant around t_k (stamps are the true instants)"},
      {"truth.timing.stamp_error", "number", "0", "[0, inf)", "s, std of an extra stamp error; instant and stamp offsets are clipped to +-0.45 of the sampling gap"},
      {"truth.timing.drop_fraction", "number", "0", "[0, 1] (1 refused)", "each sample lost with this probability"},
      {"truth.timing.imu_clock_offset", "number", "0", "[-1, 1]", "s: the IMU channels (accel_*, gyro_*) are read this long before their stamp, the suspension's at theirs (a clock offset between the two devices)"},
      {"truth.timing.seed", "unsigned", "1", "[0, 2^64)", "the timing's own generator (the noise draws stay as they are)"},
      {"truth.schedule", "list", "[]", "changes, times increasing", "quasi-static parameter changes: at each time the state carries over and integration goes on with the new parameters; `synthesize_bag` then writes `ground_truth` per sample"},
      {"truth.load_change", "choice", "jump", "jump or settle", "how the body meets a scheduled change: `jump` keeps the state's deviations from the static equilibrium, so the body is at the new equilibrium at once; `settle` keeps every mass where it is, so the body sinks and tilts to it over the suspension's own motion as a real load change does (the roll plane; other models jump)"},
      {"truth.schedule[i].time", "number", "required", "(0, inf), after the previous change", "s"},
      {"truth.schedule[i].xi", "numbers", "the previous values", "one per uncertain: entry (or values:)", "every germ coordinate from `time` on"},
      {"truth.schedule[i].values.<name>", "number", "the previous value", "any (or xi:)", "the physical value of an uncertain parameter from `time` on; the ones not named keep theirs"},
      // numerics
      {"integration.method", "choice", "rk4", "rk4 or dp5", "fixed-step integrator between the road's kinks: rk4 (classical) or dp5 (Dormand-Prince 5); accuracy and cost: [performance.md](performance.md#integrator)"},
      {"integration.max_step", "number", "0.001", "(0, 1]", "step bound, s"},
      // the filters
      {"filter.update", "choice", "square_root", "square_root or paper", "the PC Kalman update ([method.md §4.2-4.3](method.md))"},
      {"filter.es_mda.alphas", "numbers", "[4, 4, 4, 4]", "1 to 100 positive numbers with sum(1/alpha) = 1", "ES-MDA: the inflation of each pass ([method.md §4.5](method.md))"},
      {"filter.es_mda.restarts", "integer", "0", "[0, 100]", "ES-MDA and the whole-set update: re-runs from a working prior around the last result (std = `width` x its std), each reported with the working prior's information replaced by the prior's ([method.md §4.5](method.md)); 0 = one run from the prior"},
      {"filter.es_mda.width", "number", "2", "(1, inf)", "the restarts' working prior std, as a multiple of the last result's std"},
      {"filter.es_mda.covariance", "choice", "passes", "passes or local", "ES-MDA and the whole-set update: the covariance reported; local: the model's Gauss-Newton information at the passes' mean (J^T R^-1 J by central differences, 2 n + 1 runs of the record) plus the prior's, the mean the passes'; the posterior-predictive check then runs at the mode near that mean ([method.md §4.5, §5.4](method.md)); passes: the passes' own, which reads a curved posterior ridge's bend as information"},
      {"filter.enkf.members", "integer", "200", "[2, 10000000]", "EnKF ensemble size"},
      {"filter.enkf.seed", "unsigned", "7", "[0, 2^64)", "EnKF seed"},
      {"filter.enkf.update", "choice", "perturbed", "perturbed or square_root", "perturbed observations (baseline) or square_root (EAKF, diagnosis)"},
      {"filter.grid.coarse_points", "integer", "101", "[3, 100001]", "reference posterior ([method.md §4.6](method.md)): points per germ dimension on the prior support"},
      {"filter.grid.fine_points", "integer", "33", "[5, 100001]", "points per principal axis around each mode"},
      {"filter.grid.fine_span_sigmas", "number", "8", "(0, inf)", "half-width of the fine grid, in standard deviations"},
      {"filter.grid.border_mass_tolerance", "number", "1e-06", "(0, 1]", "largest posterior mass allowed on the coarse grid's border"},
      {"filter.grid.threads", "integer", "2", "[1, 256]", "threads of the grid evaluation"},
      {"filter.support", "choice", "damp", "damp or ignore", "damp: an update that would move a parameter mean out of its prior support is scaled down to stay inside, and the result is flagged unhealthy; ignore: no rule"},
      {"filter.drift_relative", "numbers", "[]", ">= 0, one per uncertain: entry (or per estimated parameter)", "one-step: as filter.drift, in fractions of each parameter's nominal per sqrt(s) (2e-4: a damper of 700 N s/m by 0.14 N s/m per sqrt(s), 8.4 over an hour), added to filter.drift in quadrature, not over an interval ending at a recognised stop (measurement.standstill); lets vehicle values that change with temperature and wear (dampers, tyres, springs) walk, which also bounds what a long drive claims about them ([method.md §4.11](method.md))"},
      {"filter.drift", "numbers", "[]", ">= 0, one per uncertain: entry (or per estimated parameter)", "one-step: random-walk std per sqrt(s) in each parameter's units (e.g. [2.0, 0.0]: M may change by 2 kg/sqrt(s)); [] = constant parameters; tolerances do not drift ([method.md §5.7](method.md))"},
      {"filter.reopen.mode", "choice", "off", "off, width, prior or load", "one-step: when the windowed NIS stays above its upper bound for `after` samples: width = re-open to width x prior std around the current mean (a parameter already wider keeps its spread); prior = back to the prior; load (linearization mean) = the load's parameters (added_mass...) back to their prior, the vehicle values kept, reported as a load change; off = never (only `~reset` re-opens) ([method.md §5.8](method.md))"},
      {"filter.reopen.width", "number", "0.5", "(0, inf)", "std after re-opening, as a fraction of the prior std"},
      {"filter.reopen.after", "integer", "3", "[1, 100000000]", "consecutive violating samples before a re-open"},
      {"filter.linearization", "choice", "collocation", "collocation or mean", "one-step: collocation = the paper's update, the observation projected over the PC spread; mean = the model's Jacobian at the mean (finite differences, one run per parameter and sample) over a moving horizon whose windows are re-run linearised at their final mean; for models whose readings follow from their inputs (road.source: none) ([method.md §4.11](method.md))"},
      {"filter.horizon.window", "number", "2", "(0, inf)", "s (linearization mean): the samples kept for a re-run; at the window's end its posterior becomes the next window's prior"},
      {"filter.horizon.shift", "number", "0.5", "(0, inf)", "a window is re-run when a sample was linearised further than this many posterior std from the window's final mean"},
      {"filter.horizon.reruns", "integer", "3", "[0, 100]", "Gauss-Newton re-runs per window at most"},
      {"filter.horizon.clock_offset", "number", "0", "[0, 1]", "s (linearization mean, road-free roll plane with its IMU): prior std of a constant offset between the IMU's stamps and the suspension's, estimated as one more state (0: not estimated); the IMU enters 3 prior std and a sample late; reported as clock_offset"},
      {"filter.horizon.cross_fall", "number", "0", "[0, 0.5]", "rad (linearization mean, road-free roll plane with its IMU; other linearizations do not read it; the batch methods es_mda and whole_set marginalise it, constant, with the two biases: [method.md §4.12](method.md)): prior std of the road's cross-fall at the start, the whole vehicle's tilt that the travels and the gyro do not see (a 2 % cross-fall is 0.02); estimated as the roll angle's error, which then enters the model's roll (the body's moments too) and no longer the load's position; a crown that changes later is seen by the gyro; 0 with the others 0: not estimated; reported as nuisance.cross_fall_rad ([method.md §4.12](method.md))"},
      {"filter.horizon.cross_fall_walk", "number", "0", "[0, 1]", "rad/sqrt(s): random walk of that angle beyond the gyro noise's (a tilt the gyro does not follow); 0: none"},
      {"filter.horizon.accel_bias", "number", "0", "[0, 10]", "m/s^2: prior std of constant biases of accel_y and accel_z, estimated as two more states (0: not estimated; the batch methods marginalise them); reported as nuisance.accel_y_bias, accel_z_bias"},
      {"filter.horizon.input_noise", "choice", "sample", "sample or state", "road-free, linearization mean: how the suspension readings' noise (the model's inputs) enters; sample = as each sample's inherited covariance alone; state = as states of the filter, each input's noise at the sample and at the one before, so that the noise a blended travel or a stop's mean shares with the samples that follow is counted once ([method.md §4.11](method.md))"},
      {"filter.horizon.mass_scale_unobservable", "bool", "true", "true or false", "linearization mean: no reading changes when every estimated mass, stiffness, damper rate and inertia is scaled by one factor, so each update's slope along that direction (at the prior's mean) is set to 0 and the scale keeps the prior's information; without it, updates linearised at different points inform the scale together and walk the estimate along it over long drives ([method.md §4.11](method.md)). A config that fixes a mass-scale value the model uses makes the scale observable through it: set false there"},
      {"filter.horizon.gyro_bias", "number", "0", "[0, 1]", "rad/s: prior std of a constant gyro_x bias, estimated as one more state whose drift (bias x time) the model's roll takes off (0: not estimated; the batch methods marginalise it); reported as nuisance.gyro_x_bias"},
      {"truth.cross_fall.start", "number", "0", "[-0.5, 0.5]", "rad, left side up > 0 (synthetic drives): the road's cross-fall under the truth from t = 0 (0.02: 2 %); the vehicle tilted rigidly with it, its gravity share g sin(beta) a lateral specific force on the truth model"},
      {"truth.cross_fall.end", "number", "0 (start when absent)", "[-0.5, 0.5]", "rad: the cross-fall after the change (a crown from +2 % to -2 %: start 0.02, end -0.02); the gyro_x reading turns with it"},
      {"truth.cross_fall.at", "number", "0", "[0, inf)", "s: the change begins (at speed V: V at metres into the drive)"},
      {"truth.cross_fall.over", "number", "0", "[0, inf)", "s: the change's length, a half-cosine (0: a step)"},
      {"filter.horizon.step", "number", "1e-04", "(0, 0.1]", "finite-difference step of the Jacobian, in prior std"},
      {"filter.relinearize.shrink", "number", "0", "[0, 0.999] (shrink x width < 1)", "one-step re-linearisation ([method.md §4.9](method.md)): when a parameter's std falls below shrink x its start, start again from a working prior around the estimate (std = width x std) and re-run the kept samples; 0 = off (the paper's filter)"},
      {"filter.relinearize.width", "number", "20", "(0, inf) (shrink x width < 1)", "working prior std, as a multiple of the current std"},
      {"filter.relinearize.max_restarts", "integer", "4", "[1, 100]", "re-linearisations at most"},
      {"filter.relinearize.max_samples", "integer", "5000", "[1, 100000000]", "samples kept for a re-run; more end re-linearisation"},
      {"filter.relinearize.defer", "number", "0", "[0, 1000]", "a re-run due after sample k runs on a worker thread while the filter goes on; its state replaces the filter's after sample k + ceil(defer k); 0 = within sample k ([realtime.md](realtime.md))"},
      {"filter.relinearize.prior_correction", "bool", "false", "true or false", "one-step: after a re-linearisation, report the posterior with the working prior's information replaced by the prior's (Gaussian in the parameters), so that a narrow working prior neither counts the data twice nor loses what only the prior bounds ([method.md §4.9](method.md))"},
      // health
      {"health.nis_window", "integer", "10", "[1, 1000000]", "samples in the windowed NIS mean ([method.md §5](method.md))"},
      {"health.nis_confidence", "number", "0.99", "(0, 1]", "two-sided confidence of every chi-square bound"},
      {"health.coherence_decimation", "integer", "10", "[2, 1000000]", "the coherence filter sees every k-th sample"},
      {"health.coherence_threshold", "number", "3", "(0, inf)", "flag above this many combined std"},
      {"health.innovation_gate", "number", "0", "[0, 0.5]", "one-step: a sample whose NIS exceeds the chi-square quantile 1 - innovation_gate is not used (counted, reported); 0 = off"},
      {"health.predictive_check", "bool", "true", "true or false", "batch methods: simulate at the posterior mean; a normalised residual sum of squares outside its chi-square bounds (nis_confidence, dof = observed entries - parameters; road-free, widened by the noise neighbouring samples share, method.md §5.4) -> not healthy"},
      {"health.rate_window", "number", "10", "(0, inf)", "one-step: s; the safeguards' rates (gated, damped, re-opened, support-exceeded samples) are judged over the last rate_window s and over the run ([method.md §5.9](method.md))"},
      {"health.reopen_interval", "number", "60", "(0, inf)", "one-step: expected s between load changes; re-opens are judged against a Poisson rate of 1 / reopen_interval per s"},
      // parameter PDFs
      {"pdf.draws", "integer", "100000", "[100, 100000000]", "germ draws of the sampled PDFs"},
      {"pdf.bins", "integer", "60", "[2, 100000]", "histogram bins"},
      {"pdf.seed", "unsigned", "11", "[0, 2^64)", "seed of the draws"},
      {"pdf.shared_draws", "bool", "false", "true or false", "true: one set of germ draws for every parameter (cost independent of n); false: parameter i draws with seed + i (the paper configs' numbers)"},
      // estimator_node only
      {"node.joints.<suspension>", "text", "<suspension>_suspension", "distinct names", "JointState name of each suspension; roll plane: `left` (u1, v1), `right` (u2, v2); full car: `front_left`, `front_right`, `rear_left`, `rear_right`"},
      {"node.reset_on_time_jump", "bool", "false", "true or false", "stamps going back by more than time_jump_tolerance (looped bag, `/clock` reset): true = reset to the prior, false = drop the message"},
      {"node.time_jump_tolerance", "number", "0.5", "[0, 1e+06]", "s; a smaller step back is out of order (dropped)"},
      {"node.publish_pdf", "bool", "true", "true or false", "publish `parameter_pdf`"},
      {"node.pdf_every", "integer", "1", "[1, 1000000000]", "publish `parameter_pdf` every k-th sample"},
      {"node.derived_every", "integer", "10", "[1, 1000000000]", "derived quantities (cg_height, static_stability_factor, rollover_threshold) projected every k-th sample, and at every `parameter_pdf`, load change and re-linearisation; an estimate between carries the latest (`derived_sample_index`); 1: every estimate its own (a projection costs milliseconds over many germs)"},
      {"node.road_wait_timeout", "number", "0.5", "[0, 3600]", "s (wall clock): a sample waits for road data covering its stamp while road messages keep arriving; after this long without any it goes on with the road held at its last value"},
      {"node.max_pending_samples", "integer", "1000", "[1, 100000000]", "samples waiting for road data (the oldest is forced beyond), also for `imu/data`"},
      {"node.imu_max_gap", "number", "0.1", "[1e-06, 3600]", "s: two `imu/data` messages further apart do not bracket a sample (it goes on without IMU channels); the bag reader applies it too"},
      {"node.max_batch_samples", "integer", "100000", "[1, 100000000]", "samples kept for `~estimate_batch` (the first ones)"},
      {"node.max_road_samples", "integer", "1000000", "[2, 1000000000]", "road samples kept (about 17 min at 1 kHz); beyond, the road before the filter's time is dropped and `~estimate_batch` is unavailable until `~reset`"},
      {"node.queue_size", "integer", "20000", "[1, 100000000]", "subscriber and publisher queues (holds a full-speed replay)"},
      {"node.coherence_check", "bool", "true", "true or false", "run a second filter on every health.coherence_decimation-th sample; its disagreement goes into the messages"},
      {"node.batch_method", "choice", "es_mda", "es_mda or whole_set", "`~estimate_batch`: es_mda (filter.es_mda.alphas) or whole_set"},
  };
  return keys;
}

std::string configSection(const std::string& path) {
  return path.substr(0, path.find_first_of(".["));
}

std::string configSchemaMarkdown(const std::vector<std::string>& sections) {
  const auto cell = [](const std::string& text, bool code) {
    if (code) return "`" + text + "`";
    // Outside `code`, a bare | would end the cell and <name> read as HTML.
    std::string out;
    bool in_code = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
      in_code ^= text[i] == '`';
      const bool escaped = i > 0 && text[i - 1] == '\\';
      if (!in_code && !escaped && (text[i] == '|' || text[i] == '<')) out += '\\';
      out += text[i];
    }
    return out;
  };
  std::string out = "| key | type | default | domain | meaning |\n|---|---|---|---|---|\n";
  for (const std::string& section : sections) {
    for (const ConfigKey& k : configSchema()) {
      if (configSection(k.path) != section) continue;
      out += "| " + cell(k.path, true) + " | " + cell(k.type, false) + " | " +
             cell(k.default_value, false) + " | " + cell(k.domain, false) + " | " +
             cell(k.meaning, false) + " |\n";
    }
  }
  return out;
}

}  // namespace pc_ekf
