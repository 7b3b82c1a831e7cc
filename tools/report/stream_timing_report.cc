#include <calib/tools/report/stream_timing_report.h>

#include <cstdio>

namespace calib {

nlohmann::json StreamTimingJson(const std::vector<StreamTiming>& streams) {
  nlohmann::json out = nlohmann::json::array();
  for (const StreamTiming& t : streams) {
    out.push_back({{"stream", t.stream},
                   {"source", t.source},
                   {"records", t.records},
                   {"samples", t.samples},
                   {"duplicates_dropped", t.duplicates_dropped},
                   {"repeated_values", t.repeated_values},
                   {"period_s", t.period_s},
                   {"jitter_s", t.jitter_s},
                   {"gaps", t.gaps},
                   {"longest_gap_s", t.longest_gap_s},
                   {"multiple_fraction", t.multiple_fraction},
                   {"regular", t.regular},
                   {"free_running_signature", t.free_running_signature},
                   {"stamps_are_sample_times", t.stamps_are_sample_times},
                   {"intervals", t.intervals},
                   {"interval_correlation", t.interval_correlation},
                   {"pickup_scatter_s", t.pickup_scatter_s},
                   {"steady_steps", t.steady_steps},
                   {"step_multiple_fraction", t.step_multiple_fraction},
                   {"step_multiples_detected", t.step_multiples_detected},
                   {"values_quantized", t.values_quantized},
                   {"notes", t.notes}});
  }
  return out;
}

std::string StreamTimingSummary(const std::vector<StreamTiming>& streams) {
  std::string text;
  char line[512];
  for (const StreamTiming& t : streams) {
    std::snprintf(
        line, sizeof(line),
        "  timing of %s: %d samples, period %.4g ms, jitter %.3g ms, %d duplicate(s) "
        "dropped, %d gap(s); %s\n",
        t.source.empty() ? t.stream.c_str() : t.source.c_str(), t.samples, t.period_s * 1e3,
        t.jitter_s * 1e3, t.duplicates_dropped, t.gaps,
        t.stamps_are_sample_times ? "stamps taken as sample times" : "stamps are NOT sample times");
    text += line;
    if (t.stamps_are_sample_times && !t.free_running_signature) continue;
    // The first note repeats the line above.
    for (size_t k = 1; k < t.notes.size(); ++k) text += "    " + t.notes[k] + "\n";
  }
  return text;
}

nlohmann::ordered_json LoggedTimingTruthJson(const LoggedTimingTruth& timing) {
  return {{"sensor_rows", timing.sensor_sample_time_s.size()},
          {"encoder_rows", timing.encoder_sample_time_s.size()},
          {"sensor_duplicates", timing.sensor_duplicates},
          {"encoder_duplicates", timing.encoder_duplicates},
          {"skipped_samples", timing.skipped_samples},
          {"held_samples", timing.held_samples},
          {"sensor_sample_time", timing.sensor_sample_time_s},
          {"encoder_sample_time", timing.encoder_sample_time_s}};
}

}  // namespace calib
