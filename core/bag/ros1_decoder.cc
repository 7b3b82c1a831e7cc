#include <calib/core/bag/ros1_decoder.h>

#include <cstdint>
#include <cstring>
#include <string>

namespace calib::ros1 {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the decoder copies little-endian numbers as they are");

// Reads fields in order; the first read past the end records which field and where, and every
// later read returns zeros, so that a decoder checks the status once at the end.
class Cursor {
 public:
  explicit Cursor(std::string_view bytes) : bytes_(bytes) {}

  template <typename T>
  T Read(const char* field) {
    T value{};
    if (Need(sizeof(T), field)) {
      std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
      pos_ += sizeof(T);
    }
    return value;
  }
  double Time(const char* field) {
    const uint32_t sec = Read<uint32_t>(field), nsec = Read<uint32_t>(field);
    return sec + nsec * 1e-9;
  }
  std::string String(const char* field) {
    const uint32_t len = Read<uint32_t>(field);
    if (!Need(len, field)) return {};
    std::string s(bytes_.data() + pos_, len);
    pos_ += len;
    return s;
  }
  // A variable array of numbers: u32 count, then count elements.
  template <typename T>
  void Array(const char* field, std::vector<T>* values) {
    const uint32_t count = Read<uint32_t>(field);
    values->clear();
    if (!Need(uint64_t{count} * sizeof(T), field)) return;
    values->resize(count);
    if (count > 0) std::memcpy(values->data(), bytes_.data() + pos_, count * sizeof(T));
    pos_ += count * sizeof(T);
  }
  std::vector<std::string> Strings(const char* field) {
    const uint32_t count = Read<uint32_t>(field);
    std::vector<std::string> values;
    // Each string takes at least its 4-byte length: bound the count before reserving.
    if (!Need(uint64_t{count} * 4, field)) return values;
    values.reserve(count);
    for (uint32_t i = 0; i < count && ok(); ++i) values.push_back(String(field));
    return values;
  }
  void Skip(uint64_t n, const char* field) {
    if (Need(n, field)) pos_ += n;
  }
  // u32 seq, time stamp, string frame_id.
  double Header(std::string* frame_id) {
    Read<uint32_t>("header.seq");
    const double stamp_s = Time("header.stamp");
    *frame_id = String("header.frame_id");
    return stamp_s;
  }
  Eigen::Vector3d Vector3(const char* field) {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v[i] = Read<double>(field);
    return v;
  }
  Eigen::Quaterniond Quaternion(const char* field) {
    const double x = Read<double>(field), y = Read<double>(field), z = Read<double>(field);
    const double w = Read<double>(field);
    return Eigen::Quaterniond(w, x, y, z);
  }

  bool ok() const { return error_.ok(); }
  // The decoding's verdict: every byte used, none missing.
  Status Finish(const char* type) const {
    if (!error_.ok()) return error_.Prefixed(std::string(type) + ": ");
    if (pos_ != bytes_.size()) {
      return Status::InvalidInput(std::string(type) + ": " + std::to_string(bytes_.size() - pos_) +
                                  " bytes left after the last field (at byte " +
                                  std::to_string(pos_) + " of " + std::to_string(bytes_.size()) +
                                  "): not this type's layout");
    }
    return Status::Ok();
  }

 private:
  bool Need(uint64_t n, const char* field) {
    if (!error_.ok()) return false;
    if (n <= bytes_.size() - pos_) return true;
    error_ = Status::InvalidInput("message of " + std::to_string(bytes_.size()) +
                                  " bytes is shorter than its fields: '" + field + "' at byte " +
                                  std::to_string(pos_) + " needs " + std::to_string(n) +
                                  " bytes, " + std::to_string(bytes_.size() - pos_) + " are left");
    return false;
  }

  std::string_view bytes_;
  size_t pos_ = 0;
  Status error_;
};

}  // namespace

Status DecodeLaserScan(std::string_view bytes, LaserScan* scan) {
  Cursor in(bytes);
  scan->stamp_s = in.Header(&scan->frame_id);
  scan->angle_min_rad = in.Read<float>("angle_min");
  in.Read<float>("angle_max");  // Implied by angle_min, the increment and the beam count.
  scan->angle_increment_rad = in.Read<float>("angle_increment");
  scan->time_increment_s = in.Read<float>("time_increment");
  scan->scan_time_s = in.Read<float>("scan_time");
  scan->range_min_m = in.Read<float>("range_min");
  scan->range_max_m = in.Read<float>("range_max");
  in.Array("ranges", &scan->ranges_m);
  in.Array("intensities", &scan->intensities);
  return in.Finish("sensor_msgs/LaserScan");
}

Status DecodeJointState(std::string_view bytes, JointState* joints) {
  Cursor in(bytes);
  joints->stamp_s = in.Header(&joints->frame_id);
  joints->name = in.Strings("name");
  in.Array("position", &joints->position);
  in.Array("velocity", &joints->velocity);
  in.Array("effort", &joints->effort);
  return in.Finish("sensor_msgs/JointState");
}

Status DecodeOdometry(std::string_view bytes, Odometry* odometry) {
  Cursor in(bytes);
  odometry->stamp_s = in.Header(&odometry->frame_id);
  odometry->child_frame_id = in.String("child_frame_id");
  odometry->position = in.Vector3("pose.pose.position");
  odometry->orientation = in.Quaternion("pose.pose.orientation");
  in.Skip(36 * sizeof(double), "pose.covariance");
  odometry->linear_velocity = in.Vector3("twist.twist.linear");
  odometry->angular_velocity = in.Vector3("twist.twist.angular");
  in.Skip(36 * sizeof(double), "twist.covariance");
  return in.Finish("nav_msgs/Odometry");
}

Status DecodeTfMessage(std::string_view bytes, std::vector<TransformStamped>* transforms) {
  Cursor in(bytes);
  const uint32_t count = in.Read<uint32_t>("transforms");
  // A TransformStamped takes at least 4 + 8 + 4 + 4 + 7 × 8 bytes: bound the count first.
  if (uint64_t{count} * 76 > bytes.size()) {
    return Status::InvalidInput("tf2_msgs/TFMessage: message of " + std::to_string(bytes.size()) +
                                " bytes is shorter than its fields: " + std::to_string(count) +
                                " transforms need at least " + std::to_string(count * 76ull) +
                                " bytes");
  }
  std::vector<TransformStamped> decoded;
  decoded.reserve(count);
  for (uint32_t i = 0; i < count && in.ok(); ++i) {
    TransformStamped t;
    t.stamp_s = in.Header(&t.parent_frame);
    t.child_frame = in.String("transforms[].child_frame_id");
    t.translation = in.Vector3("transforms[].transform.translation");
    t.rotation = in.Quaternion("transforms[].transform.rotation");
    decoded.push_back(std::move(t));
  }
  CALIB_RETURN_IF_ERROR(in.Finish("tf2_msgs/TFMessage"));
  transforms->insert(transforms->end(), decoded.begin(), decoded.end());
  return Status::Ok();
}

}  // namespace calib::ros1
