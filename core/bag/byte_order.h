#ifndef CALIB_CORE_BAG_BYTE_ORDER_H_
#define CALIB_CORE_BAG_BYTE_ORDER_H_

#include <algorithm>
#include <cstddef>
#include <cstring>

// The byte order of serialized ROS messages: the host's, and the CDR encapsulation header (2
// bytes of representation, 00 00 big- or 00 01 little-endian, then 2 of options) before every
// ROS 2 message, for the CDR decoder (cdr_decoder.h) and the decoder of any type
// (message_definition.h).
namespace calib {

inline constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
inline constexpr size_t kCdrHeaderBytes = 4;

template <typename T>
T ByteSwapped(T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  std::reverse(bytes, bytes + sizeof(T));
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

}  // namespace calib

#endif  // CALIB_CORE_BAG_BYTE_ORDER_H_
