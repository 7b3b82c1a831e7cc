#ifndef CALIB_CORE_SCAN_SCAN_CSV_H_
#define CALIB_CORE_SCAN_SCAN_CSV_H_

#include <calib/core/scan/laser_scan.h>
#include <calib/core/status.h>

#include <string>
#include <string_view>
#include <vector>

// Raw scans as CSV, for logs that are not bags. Two layouts (the header tells which):
// - wide, one scan per row:
//     t,angle_min,angle_increment[,time_increment][,range_min][,range_max],range_0,range_1,...
// - long, one beam per row, the rows of a scan sharing t (and contiguous):
//     t,angle,range[,time_increment][,range_min][,range_max]
// A range cell that is empty, nan or inf (any sign, any case) is no return. t must increase from
// scan to scan, but for a scan written twice (every value repeated: kept here, dropped with a
// warning by LaserLogFromScans). Ranges are floats; the writer's text reads back to the same float.
namespace calib {

enum class ScanCsvLayout { kWide, kLong };

// `source` names the text in messages ("file:line: record n: ...").
StatusOr<std::vector<LaserScan>> ParseScanCsv(std::string_view text, const std::string& source);
StatusOr<std::vector<LaserScan>> ReadScanCsv(const std::string& path);

// In the long layout a scan's beam angles are written as angle_min + i·angle_increment, and read
// back as angle_min = the first angle and angle_increment = (last − first)/(n − 1).
std::string FormatScanCsv(const std::vector<LaserScan>& scans, ScanCsvLayout layout);
Status WriteScanCsv(const std::vector<LaserScan>& scans, ScanCsvLayout layout,
                    const std::string& path);

}  // namespace calib

#endif  // CALIB_CORE_SCAN_SCAN_CSV_H_
