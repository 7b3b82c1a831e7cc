#include <calib/core/bag/byte_order.h>
#include <calib/core/bag/cdr_decoder.h>

#include <cstring>
#include <string>
#include <type_traits>

namespace calib {
namespace {

// A cursor over one CDR message. The first failure sticks: later reads do nothing and status()
// names the field and byte where the message fell short.
class CdrReader {
 public:
  CdrReader(const uint8_t* data, size_t size) : data_(data), size_(size) {
    if (size < kCdrHeaderBytes) {
      Fail("encapsulation header");
    } else if (data[0] != 0 || data[1] > 1) {
      error_ = "unsupported CDR encapsulation 0x" + Hex(data[0]) + Hex(data[1]) +
               " (plain CDR, XCDR1, is read)";
    } else {
      swap_ = (data[1] == 1) != kHostLittleEndian;
      pos_ = kCdrHeaderBytes;
    }
  }

  bool ok() const { return error_.empty(); }
  Status status() const { return ok() ? Status::Ok() : Status::InvalidInput(error_); }

  template <typename T>
  T Read(const char* field) {
    static_assert(std::is_arithmetic<T>::value, "CDR primitive");
    T value{};
    if (!Align(sizeof(T), field) || !Need(sizeof(T), field)) return value;
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return swap_ ? ByteSwapped(value) : value;
  }

  std::string ReadString(const char* field) {
    const uint32_t n = Read<uint32_t>(field);
    if (!Need(n, field)) return {};
    const char* text = reinterpret_cast<const char*>(data_ + pos_);
    pos_ += n;
    return std::string(text, n > 0 && text[n - 1] == '\0' ? n - 1 : n);
  }

  // A sequence's count, checked against the bytes left (each item takes at least min_item_bytes).
  uint32_t ReadCount(size_t min_item_bytes, const char* field) {
    const uint32_t n = Read<uint32_t>(field);
    if (ok() && n > (size_ - pos_) / min_item_bytes) {
      error_ = std::string("field '") + field + "' at byte " + std::to_string(pos_) + " counts " +
               std::to_string(n) + " items, more than the " + std::to_string(size_ - pos_) +
               " bytes left hold";
      return 0;
    }
    return ok() ? n : 0;
  }

  template <typename T>
  void ReadSequence(std::vector<T>* out, const char* field) {
    const uint32_t n = ReadCount(sizeof(T), field);
    out->clear();
    if (n == 0 || !Align(sizeof(T), field) || !Need(n * sizeof(T), field)) return;
    out->resize(n);
    std::memcpy(out->data(), data_ + pos_, n * sizeof(T));
    pos_ += n * sizeof(T);
    if (swap_) {
      for (T& v : *out) v = ByteSwapped(v);
    }
  }

  void Skip(size_t count, size_t item_bytes, const char* field) {
    if (!Align(item_bytes, field) || !Need(count * item_bytes, field)) return;
    pos_ += count * item_bytes;
  }

 private:
  static std::string Hex(uint8_t b) {
    const char* digits = "0123456789abcdef";
    return {digits[b >> 4], digits[b & 15]};
  }
  bool Align(size_t n, const char* field) {
    if (!ok()) return false;
    const size_t pad = (n - (pos_ - kCdrHeaderBytes) % n) % n;
    return Need(pad, field) && (pos_ += pad, true);
  }
  bool Need(size_t n, const char* field) {
    if (!ok()) return false;
    if (n > size_ - pos_) {
      Fail(field);
      return false;
    }
    return true;
  }
  void Fail(const char* field) {
    error_ = "CDR message of " + std::to_string(size_) + " bytes ends at byte " +
             std::to_string(pos_) + " before its field '" + field + "'";
  }

  const uint8_t* data_;
  size_t size_, pos_ = 0;
  bool swap_ = false;
  std::string error_;
};

// std_msgs/Header: builtin_interfaces/Time stamp {int32 sec, uint32 nanosec}, string frame_id.
double ReadHeader(CdrReader* cdr, std::string* frame_id) {
  const int32_t sec = cdr->Read<int32_t>("header.stamp.sec");
  const uint32_t nanosec = cdr->Read<uint32_t>("header.stamp.nanosec");
  *frame_id = cdr->ReadString("header.frame_id");
  return sec + 1e-9 * nanosec;
}

Eigen::Vector3d ReadVector3(CdrReader* cdr, const char* field) {
  const double x = cdr->Read<double>(field), y = cdr->Read<double>(field);
  return {x, y, cdr->Read<double>(field)};
}

Eigen::Quaterniond ReadQuaternion(CdrReader* cdr, const char* field) {
  const double x = cdr->Read<double>(field), y = cdr->Read<double>(field);
  const double z = cdr->Read<double>(field), w = cdr->Read<double>(field);
  return Eigen::Quaterniond(w, x, y, z);
}

}  // namespace

Status DecodeLaserScan(const uint8_t* data, size_t size, LaserScan* scan) {
  CdrReader cdr(data, size);
  scan->stamp_s = ReadHeader(&cdr, &scan->frame_id);
  scan->angle_min_rad = cdr.Read<float>("angle_min");
  cdr.Read<float>("angle_max");  // Implied by angle_min, angle_increment and the beam count.
  scan->angle_increment_rad = cdr.Read<float>("angle_increment");
  scan->time_increment_s = cdr.Read<float>("time_increment");
  scan->scan_time_s = cdr.Read<float>("scan_time");
  scan->range_min_m = cdr.Read<float>("range_min");
  scan->range_max_m = cdr.Read<float>("range_max");
  cdr.ReadSequence(&scan->ranges_m, "ranges");
  cdr.ReadSequence(&scan->intensities, "intensities");
  return cdr.status();
}

Status DecodeJointState(const uint8_t* data, size_t size, JointState* joints) {
  CdrReader cdr(data, size);
  joints->stamp_s = ReadHeader(&cdr, &joints->frame_id);
  const uint32_t n = cdr.ReadCount(4, "name");
  joints->name.clear();
  for (uint32_t i = 0; i < n && cdr.ok(); ++i) joints->name.push_back(cdr.ReadString("name"));
  cdr.ReadSequence(&joints->position, "position");
  cdr.ReadSequence(&joints->velocity, "velocity");
  cdr.ReadSequence(&joints->effort, "effort");
  CALIB_RETURN_IF_ERROR(cdr.status());
  // Each array is empty or holds one value per name (sensor_msgs/JointState's rule).
  for (const auto& [field, values] :
       {std::pair<const char*, const std::vector<double>*>{"position", &joints->position},
        {"velocity", &joints->velocity},
        {"effort", &joints->effort}}) {
    if (!values->empty() && values->size() != joints->name.size()) {
      return Status::InvalidInput("JointState field '" + std::string(field) + "' holds " +
                                  std::to_string(values->size()) + " values for " +
                                  std::to_string(joints->name.size()) + " names");
    }
  }
  return Status::Ok();
}

// nav_msgs/Odometry: header, child_frame_id, pose {pose {position, orientation}, covariance[36]},
// twist {twist {linear, angular}, covariance[36]}.
Status DecodeOdometry(const uint8_t* data, size_t size, Odometry* odometry) {
  CdrReader cdr(data, size);
  odometry->stamp_s = ReadHeader(&cdr, &odometry->frame_id);
  odometry->child_frame_id = cdr.ReadString("child_frame_id");
  odometry->position = ReadVector3(&cdr, "pose.pose.position");
  odometry->orientation = ReadQuaternion(&cdr, "pose.pose.orientation");
  cdr.Skip(36, sizeof(double), "pose.covariance");
  odometry->linear_velocity = ReadVector3(&cdr, "twist.twist.linear");
  odometry->angular_velocity = ReadVector3(&cdr, "twist.twist.angular");
  cdr.Skip(36, sizeof(double), "twist.covariance");
  return cdr.status();
}

Status DecodeTfMessage(const uint8_t* data, size_t size,
                       std::vector<TransformStamped>* transforms) {
  CdrReader cdr(data, size);
  // Each geometry_msgs/TransformStamped holds at least 8 + 4 + 4 + 7 * 8 bytes.
  const uint32_t n = cdr.ReadCount(72, "transforms");
  for (uint32_t i = 0; i < n && cdr.ok(); ++i) {
    TransformStamped t;
    t.stamp_s = ReadHeader(&cdr, &t.parent_frame);
    t.child_frame = cdr.ReadString("transforms.child_frame_id");
    t.translation = ReadVector3(&cdr, "transforms.transform.translation");
    t.rotation = ReadQuaternion(&cdr, "transforms.transform.rotation");
    if (cdr.ok()) transforms->push_back(std::move(t));
  }
  return cdr.status();
}

}  // namespace calib
