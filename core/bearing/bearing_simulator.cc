#include <calib/core/bearing/bearing_simulator.h>
#include <calib/core/random.h>
#include <calib/core/timing/logging_model.h>

#include <algorithm>
#include <cmath>

namespace calib {
namespace {

// One integration step: wheel speeds held constant from `t_s` for `duration_s`.
struct Step {
  double t_s = 0.0;
  double duration_s = 0.0;
  WheelSpeeds speeds;
  Pose2d world_T_robot_start = Pose2d::Zero();
};

Pose2d AdvanceTruth(const BearingSimOptions& o, const Pose2d& pose, const WheelSpeeds& speeds,
                    double dt_s) {
  const BearingMetricParams& m = o.truth;
  const double r = o.wheel_radius_m;
  return Compose(pose,
                 EncoderStepDisplacement(r, o.wheelbase_m, m.delta_r, m.delta_l, m.delta_b,
                                         speeds.left_mps * dt_s / r, speeds.right_mps * dt_s / r));
}

// The wheel speeds of a run at time t from its start: vR = ν, vL = q·ν on a circular run.
WheelSpeeds SpeedsAt(const BearingSimOptions& options, const BearingRunSpec& spec, double t) {
  const bool circular = !spec.wheel_speeds;
  const double nu = options.right_wheel_speed_mps;
  return circular ? WheelSpeeds{spec.q * nu, nu} : spec.wheel_speeds(t);
}

// The run's length in seconds: its duration_s, else its loops of a circle (60 s if it does not
// turn).
double RunDuration(const BearingSimOptions& options, const BearingRunSpec& spec) {
  const BearingMetricParams& m = options.truth;
  const double b = options.wheelbase_m;
  const bool circular = !spec.wheel_speeds;
  const double nu = options.right_wheel_speed_mps;
  double duration = spec.duration_s;
  if (!(duration > 0.0)) {
    const double omega = (m.delta_r * nu - m.delta_l * spec.q * nu) / (m.delta_b * b);
    duration = circular && omega != 0.0 ? spec.loops * 2.0 * M_PI / std::abs(omega) : 60.0;
  }
  return duration;
}

// The logging model's random streams, apart from the log's own sequence; one set per run.
enum LoggingStream : uint32_t { kLoggerTiming = 101, kEncoderTiming, kEncoderRepeats, kRepeats };
uint32_t RunStream(LoggingStream stream, size_t run_index) {
  return static_cast<uint32_t>(stream + 16 * run_index);
}

// The encoder polls of a run from its start: at 0, then every encoder period (stamps = true times,
// scattered by the stamp jitter), or the logging model's scattered polls (the start and the end
// of the run then exact); the last one at the run's end.
std::vector<EncoderPoll> RunEncoderPolls(const BearingSimOptions& options, double duration,
                                         Random* timing) {
  std::vector<EncoderPoll> polls{EncoderPoll{0.0, 0.0}};
  if (options.logging.encoder_period_s > 0.0) {
    const double period = options.logging.encoder_period_s;
    for (const EncoderPoll& poll : EncoderPolls(options.logging, 0.0, duration, timing)) {
      if (poll.stamp_s > 0.3 * period && poll.stamp_s < duration - 0.3 * period &&
          poll.true_s > 0.0 && poll.true_s < duration) {
        polls.push_back(poll);
      }
    }
    polls.push_back(EncoderPoll{duration, duration});
    return polls;
  }
  std::vector<double> times{0.0};
  const double encoder_dt = 1.0 / options.encoder_rate_hz;
  for (int k = 0;; ++k) {
    const double t = k * encoder_dt;
    if (t >= duration - 1e-9 * encoder_dt) break;
    double t_next = std::min((k + 1) * encoder_dt, duration);
    if (duration - t_next < 1e-9 * encoder_dt) t_next = duration;
    times.push_back(t_next);
  }
  return StampedPolls(options.logging, times, timing);
}

// Truth: integrate in steps; encoder samples at the true poll times, appended to `odometry`
// (stamped from clock_s, with the logging model's stamp scatter and repeated rows). Returns the
// integration steps.
std::vector<Step> SimulateEncoders(const BearingSimOptions& options, const BearingRunSpec& spec,
                                   double duration, double clock_s, Random* random,
                                   size_t run_index, std::vector<EncoderSample>* odometry,
                                   LoggedTimingTruth* timing) {
  const double r = options.wheel_radius_m;
  const int substeps = std::max(1, options.integration_substeps);
  Random encoder_timing(options.seed, RunStream(kEncoderTiming, run_index));
  Random repeats(options.seed, RunStream(kEncoderRepeats, run_index));
  const std::vector<EncoderPoll> polls = RunEncoderPolls(options, duration, &encoder_timing);
  std::vector<Step> steps;
  Pose2d pose = spec.world_T_robot_start;
  std::vector<EncoderSample> samples{EncoderSample{clock_s + polls[0].stamp_s, 0.0, 0.0, 0}};
  double left_read = 0.0, right_read = 0.0;
  for (size_t k = 0; k + 1 < polls.size(); ++k) {
    const double t = polls[k].true_s;
    const double t_next = polls[k + 1].true_s;
    const double period = t_next - t;
    double left_true = 0.0, right_true = 0.0;
    for (int j = 0; j < substeps; ++j) {
      Step step;
      step.t_s = t + period * j / substeps;
      step.duration_s = period / substeps;
      step.speeds = SpeedsAt(options, spec, step.t_s + 0.5 * step.duration_s);
      step.world_T_robot_start = pose;
      pose = AdvanceTruth(options, pose, step.speeds, step.duration_s);
      left_true += step.speeds.left_mps * step.duration_s / r;
      right_true += step.speeds.right_mps * step.duration_s / r;
      steps.push_back(step);
    }
    const double k2 = options.encoder_noise_k * options.encoder_noise_k / r;
    left_read += left_true + std::sqrt(k2 * std::abs(left_true)) * random->NormalPolar();
    right_read += right_true + std::sqrt(k2 * std::abs(right_true)) * random->NormalPolar();
    samples.push_back(EncoderSample{clock_s + polls[k + 1].stamp_s, left_read, right_read, 0});
  }
  size_t previous = 0;
  for (const size_t row :
       RowsWithRepeats(samples.size(), options.logging.repeat_fraction, &repeats)) {
    timing->encoder_duplicates += row > 0 && row == previous;
    previous = row;
    odometry->push_back(samples[row]);
    timing->encoder_sample_time_s.push_back(polls[row].true_s);
  }
  return steps;
}

// The bearing sensor's true sample times from the run's start: its free-running grid, or
// every 1/bearing_rate_hz; all within [0, duration].
std::vector<double> BearingSampleTimes(const BearingSimOptions& options, double duration) {
  std::vector<double> times;
  const LoggingModel& logging = options.logging;
  if (logging.sensor_period_s > 0.0) {
    const double period = logging.sensor_period_s * (1.0 + logging.sensor_clock_drift);
    const size_t count = static_cast<size_t>(
        std::max(0.0, std::floor((duration - logging.sensor_phase_s) / period + 1e-9)) + 1);
    for (const double t : FreeRunningSampleTimes(logging, count)) {
      if (t <= duration + 1e-9) times.push_back(t);
    }
    return times;
  }
  const double bearing_dt = 1.0 / options.bearing_rate_hz;
  for (int j = 0;; ++j) {
    const double tb = j * bearing_dt;
    if (tb > duration + 1e-9) break;
    times.push_back(tb);
  }
  return times;
}

// Bearings at the sensor's sample times from the run's start, each taken at the exact true pose
// of its sample time + the time offset, then written as the logging model's logger writes them.
void SimulateBearings(const BearingSimOptions& options, const BearingRunSpec& spec,
                      const std::vector<Step>& steps, double duration, double clock_s,
                      size_t run_index, Random* random, BearingRun* run,
                      BearingRunTruth* run_truth) {
  const BearingMetricParams& m = options.truth;
  const std::vector<double> sample_times = BearingSampleTimes(options, duration);
  std::vector<BearingSample> samples;
  std::vector<Pose2d> poses;
  size_t step_index = 0;
  for (const double tb : sample_times) {
    const double taken = std::clamp(tb + options.time_offset_s, 0.0, duration);
    while (step_index + 1 < steps.size() && steps[step_index + 1].t_s <= taken) ++step_index;
    Pose2d at = spec.world_T_robot_start;
    if (!steps.empty()) {
      const Step& step = steps[step_index];
      at = AdvanceTruth(options, step.world_T_robot_start, step.speeds, taken - step.t_s);
    }
    const double clean = BearingFromPose(at, m.phi_rad, m.rho_m, m.psi_rad);
    const double noisy = WrapAngle(clean + options.bearing_noise_rad * random->NormalPolar());
    samples.push_back(BearingSample{tb, noisy, 0});
    poses.push_back(at);
  }
  Random logger(options.seed, RunStream(kLoggerTiming, run_index));
  Random repeats(options.seed, RunStream(kRepeats, run_index));
  const std::vector<LoggedSample> records = LogSamples(options.logging, sample_times, &logger);
  LoggedTimingTruth& timing = run_truth->timing;
  timing.all_sensor_sample_times_s = sample_times;
  std::vector<bool> written(samples.size(), false);
  size_t previous = 0;
  for (const size_t row :
       RowsWithRepeats(records.size(), options.logging.repeat_fraction, &repeats)) {
    const LoggedSample& record = records[row];
    // Bearings stamped outside the encoders' span could not be read back.
    const double stamp_s = clock_s + record.stamp_s;
    if (stamp_s < run->odometry.front().t_s || stamp_s > run->odometry.back().t_s) continue;
    const bool duplicate = !run->bearings.empty() && row == previous;
    timing.sensor_duplicates += duplicate;
    timing.held_samples += !duplicate && written[record.sample];
    written[record.sample] = true;
    previous = row;
    run->bearings.push_back(BearingSample{stamp_s, samples[record.sample].bearing_rad, 0});
    run_truth->world_T_robot_at_bearings.push_back(poses[record.sample]);
    timing.sensor_sample_time_s.push_back(sample_times[record.sample] + options.time_offset_s);
    timing.sensor_sample_index.push_back(record.sample);
  }
  timing.skipped_samples = std::count(written.begin(), written.end(), false);
}

// The closed-form quantities of a circular run (eqs. 3, 15, 17, 21 and its circle).
void SetCircularTruth(const BearingMetricParams& m, double b, const BearingParams& params,
                      const BearingRunSpec& spec, BearingRunTruth* run_truth) {
  run_truth->eta_q_per_m = EtaQ(params.eta_per_m, params.delta, spec.q);
  run_truth->xi_q_per_m = XiQ(params.xi_per_m, params.delta, spec.q);
  GammaMuFromPose(spec.world_T_robot_start, m.phi_rad, m.rho_m, &run_truth->gamma0_rad,
                  &run_truth->mu0);
  if (run_truth->xi_q_per_m != 0.0) {
    run_truth->circle = CircleFromStart(m, b, spec.q, spec.world_T_robot_start);
    run_truth->state0 =
        CircularStateFromGammaMu(run_truth->mu0, run_truth->gamma0_rad, m.phi_rad, m.psi_rad,
                                 run_truth->eta_q_per_m, run_truth->xi_q_per_m);
    run_truth->k_per_m =
        KFromState(run_truth->state0.A, run_truth->state0.V, run_truth->xi_q_per_m);
    run_truth->c_rad = CFromKV(run_truth->k_per_m, run_truth->state0.V, run_truth->xi_q_per_m);
  }
}

}  // namespace

std::vector<BearingRunSpec> MartinelliRuns(const Pose2d& world_T_robot_start) {
  std::vector<BearingRunSpec> runs;
  for (double q : {0.9, 0.0, -1.0}) {
    BearingRunSpec spec;
    spec.q = q;
    spec.loops = 1.0;
    spec.world_T_robot_start = world_T_robot_start;
    runs.push_back(spec);
  }
  return runs;
}

BearingRunSpec WeavingRun(double duration_s, double period_s, double swing, double speed_mps,
                          const Pose2d& world_T_robot_start) {
  BearingRunSpec spec;
  spec.wheel_speeds = [=](double t) {
    const double s = swing * std::sin(2.0 * M_PI * t / period_s);
    return WheelSpeeds{speed_mps * (1.0 - s), speed_mps * (1.0 + s)};
  };
  spec.duration_s = duration_s;
  spec.world_T_robot_start = world_T_robot_start;
  return spec;
}

BearingLog SimulateBearingLog(const BearingSimOptions& options, BearingSimTruth* truth) {
  const BearingMetricParams& m = options.truth;
  const double r = options.wheel_radius_m;
  const double b = options.wheelbase_m;
  const BearingParams params = ObservableParams(m, b);
  const std::vector<BearingRunSpec> specs = options.runs.empty() ? MartinelliRuns() : options.runs;
  // The Gaussians of std::normal_distribution under libstdc++, with any standard library.
  Random random(options.seed);

  BearingLog log;
  log.source = "simulation";
  log.meta.wheel_radius_m = r;
  log.meta.wheelbase_m = b;
  if (truth != nullptr) {
    truth->metric = m;
    truth->params = params;
    truth->runs.clear();
  }

  double clock_s = options.start_time_s;
  for (size_t i = 0; i < specs.size(); ++i) {
    const BearingRunSpec& spec = specs[i];
    const bool circular = !spec.wheel_speeds;
    const double duration = RunDuration(options, spec);

    BearingRun run;
    run.id = spec.id != 0 ? spec.id : static_cast<int>(i) + 1;
    BearingRunTruth run_truth;
    const std::vector<Step> steps = SimulateEncoders(options, spec, duration, clock_s, &random, i,
                                                     &run.odometry, &run_truth.timing);

    run_truth.id = run.id;
    run_truth.q = spec.q;
    run_truth.circular = circular;
    run_truth.world_T_robot_start = spec.world_T_robot_start;
    run_truth.initial_distance_m = spec.world_T_robot_start.head<2>().norm();
    SimulateBearings(options, spec, steps, duration, clock_s, i, &random, &run, &run_truth);
    if (circular) SetCircularTruth(m, b, params, spec, &run_truth);
    if (options.initial_distance_run == run.id) {
      log.meta.initial_distance = InitialDistance{run.id, run_truth.initial_distance_m};
    }
    if (truth != nullptr) truth->runs.push_back(run_truth);
    clock_s += duration + options.gap_between_runs_s;
    log.runs.push_back(std::move(run));
  }
  std::sort(log.runs.begin(), log.runs.end(),
            [](const BearingRun& x, const BearingRun& y) { return x.id < y.id; });
  return log;
}

}  // namespace calib
