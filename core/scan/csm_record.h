#ifndef CALIB_CORE_SCAN_CSM_RECORD_H_
#define CALIB_CORE_SCAN_CSM_RECORD_H_

#include <string_view>
#include <vector>

// One record (JSON object) of a CSM laser log, reduced to the fields the log's reader uses
// (csm_log.h). Python's json writes NaN and Infinity, which JSON has not: they read as null.
namespace calib {

struct CsmValue {
  enum class Kind { kAbsent, kNumber, kArray, kOther };
  Kind kind = Kind::kAbsent;
  double number = 0.0;        // kNumber: finite.
  std::vector<double> array;  // kArray: its elements, NaN where one is no number (null).

  bool present() const { return kind != Kind::kAbsent; }
  bool IsNumber() const { return kind == Kind::kNumber; }
  bool IsArray(size_t size) const { return kind == Kind::kArray && array.size() == size; }
};

struct CsmRecord {
  CsmValue readings, valid, theta, min_theta, max_theta, nrays, timestamp;
  CsmValue left, right, left_timestamp, right_timestamp, odometry;
};

// Parses one JSON object into *record (cleared first; its arrays keep their capacity, so that a
// reader reusing one record allocates nothing per scan). False when `bytes` are no JSON object.
// Records that hold only numbers, arrays of numbers and plain strings take a direct path
// (from_chars); anything else goes through a full JSON parser.
bool ParseCsmRecord(std::string_view bytes, CsmRecord* record);

}  // namespace calib

#endif  // CALIB_CORE_SCAN_CSM_RECORD_H_
