#ifndef CALIB_CORE_PARAM_INFO_H_
#define CALIB_CORE_PARAM_INFO_H_

// What a reader of a result needs to know of one estimated parameter: its name in the contract,
// its unit, whether it is an angle (wrapped, shown in degrees), and how a person reads it.
namespace calib {

struct ParamInfo {
  const char* name;          // Contract name, e.g. "r_l", "sensor_theta", "eta".
  const char* unit;          // SI unit of the stored value: "m", "rad", "1/m", "" (ratio).
  bool is_angle;             // Wrapped to (−π, π]; differences of it are wrapped too.
  double display_scale;      // Value × display_scale is in display_unit (e.g. 1000 for mm).
  const char* display_unit;  // "mm", "deg", "1/m", "".
};

}  // namespace calib

#endif  // CALIB_CORE_PARAM_INFO_H_
