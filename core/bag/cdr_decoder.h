#ifndef CALIB_CORE_BAG_CDR_DECODER_H_
#define CALIB_CORE_BAG_CDR_DECODER_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/status.h>

#include <cstddef>
#include <cstdint>
#include <vector>

// Decoders of the ROS 2 messages a calibration reads, from their CDR serialisation (XCDR1 / plain
// CDR, little- or big-endian, as rmw writes it): a 4-byte encapsulation header {0, kind, 0, 0}
// (kind 1 = little-endian, 0 = big-endian), then the fields, each primitive aligned to its size
// counted from the end of the header; strings and sequences are a uint32 count then the items
// (a string's count includes its terminating NUL). Each decoder fills the message fields only
// (the caller sets record and log_time_s) and fails, naming the field and the byte, when the
// message is shorter than its fields (a JointState also when an array is neither empty nor one
// value per name). stamp_s = header.stamp.sec + 1e-9 * header.stamp.nanosec.
namespace calib {

Status DecodeLaserScan(const uint8_t* data, size_t size, LaserScan* scan);
Status DecodeJointState(const uint8_t* data, size_t size, JointState* joints);
Status DecodeOdometry(const uint8_t* data, size_t size, Odometry* odometry);
// A tf2_msgs/TFMessage: its transforms appended to `transforms`.
Status DecodeTfMessage(const uint8_t* data, size_t size, std::vector<TransformStamped>* transforms);

}  // namespace calib

#endif  // CALIB_CORE_BAG_CDR_DECODER_H_
