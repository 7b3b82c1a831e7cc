#ifndef CALIB_BENCHMARKS_BENCH_PLOT_H_
#define CALIB_BENCHMARKS_BENCH_PLOT_H_

// The benchmarks draw with the one SVG writer of the tools (tools/report/svg_plot.h).
#include <calib/tools/report/svg_plot.h>

namespace calib::bench {

using ::calib::PlotPanel;
using ::calib::PlotSeries;
using ::calib::WriteLogLogSvg;

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_PLOT_H_
