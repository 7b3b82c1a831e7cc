#include <calib/core/bag/encoder_messages.h>

namespace calib {
namespace {

// The dependencies of both types' std_msgs/Header, as a ROS 2 bag stores them.
constexpr char kHeaderSections[] =
    "================================================================================\n"
    "MSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\n"
    "string frame_id\n"
    "================================================================================\n"
    "MSG: builtin_interfaces/Time\n"
    "int32 sec\n"
    "uint32 nanosec\n";

// ROBOTIS' turtlebot3_msgs (Dynamixel XL430 wheels: 4096 counts a turn).
constexpr char kTurtlebot3[] =
    "std_msgs/Header header\n"
    "uint8 bumper\n"
    "float32 cliff\n"
    "float32 sonar\n"
    "float32 illumination\n"
    "uint8 led\n"
    "uint8 button\n"
    "bool torque\n"
    "int32 left_encoder\n"
    "int32 right_encoder\n"
    "float32 battery\n";

// Yujin's Kobuki (TurtleBot 2): 16-bit counters that wrap, 2π/0.002436916871363930 counts a turn
// (the driver's ticks-to-radians factor).
constexpr char kKobuki[] =
    "std_msgs/Header header\n"
    "uint16 time_stamp\n"
    "uint8 bumper\n"
    "uint8 wheel_drop\n"
    "uint8 cliff\n"
    "uint16 left_encoder\n"
    "uint16 right_encoder\n"
    "int8 left_pwm\n"
    "int8 right_pwm\n"
    "uint8 buttons\n"
    "uint8 charger\n"
    "uint8 battery\n"
    "uint16[] bottom\n"
    "uint8[] current\n"
    "uint8 over_current\n"
    "uint16 digital_input\n"
    "uint16[] analog_input\n";

constexpr double kKobukiTicksPerTurn = 2578.333869740464;

const EncoderMessageType kTypes[] = {
    {"turtlebot3_msgs/SensorState", "left_encoder", "right_encoder", 4096.0, kTurtlebot3},
    {"kobuki_msgs/SensorState", "left_encoder", "right_encoder", kKobukiTicksPerTurn, kKobuki},
    {"kobuki_ros_interfaces/SensorState", "left_encoder", "right_encoder", kKobukiTicksPerTurn,
     kKobuki},
};

}  // namespace

std::string EncoderMessageType::Ros2Definition() const {
  return std::string(ros2_fields) + kHeaderSections;
}

const EncoderMessageType* FindEncoderMessageType(const std::string& type) {
  std::string normalised = type;
  const size_t msg = normalised.find("/msg/");
  if (msg != std::string::npos) normalised.erase(msg, 4);
  for (const EncoderMessageType& known : kTypes) {
    if (normalised == known.type) return &known;
  }
  return nullptr;
}

}  // namespace calib
