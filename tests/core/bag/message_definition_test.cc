#include <calib/core/bag/message_definition.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

namespace calib {
namespace {

const std::string kSeparator = "\n" + std::string(80, '=') + "\n";

// Messages written byte by byte, as ROS 1 (packed little-endian) or CDR (XCDR1, aligned from
// the end of the 4-byte encapsulation header, either byte order).
class Writer {
 public:
  static Writer Ros1() { return Writer(false, true); }
  static Writer Cdr(bool little_endian) { return Writer(true, little_endian); }

  template <typename T>
  Writer& Put(T value) {
    static_assert(std::is_arithmetic<T>::value, "a primitive");
    Align(sizeof(T) < 8 ? sizeof(T) : 8);
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));  // The tests run on little-endian hosts.
    for (size_t i = 0; i < sizeof(T); ++i) {
      bytes_.push_back(bytes[little_endian_ ? i : sizeof(T) - 1 - i]);
    }
    return *this;
  }
  Writer& String(const std::string& s) {
    Put<uint32_t>(static_cast<uint32_t>(s.size() + (cdr_ ? 1 : 0)));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    if (cdr_) bytes_.push_back(0);
    return *this;
  }
  Writer& Raw(std::vector<uint8_t> raw) {
    bytes_.insert(bytes_.end(), raw.begin(), raw.end());
    return *this;
  }
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  Writer(bool cdr, bool little_endian) : cdr_(cdr), little_endian_(little_endian) {
    if (cdr) bytes_ = {0, static_cast<uint8_t>(little_endian ? 1 : 0), 0, 0};
  }
  void Align(size_t n) {
    if (!cdr_) return;
    while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
  }

  bool cdr_;
  bool little_endian_;
  std::vector<uint8_t> bytes_;
};

StatusOr<std::vector<double>> Read(const MessageDefinition& definition,
                                   const std::vector<uint8_t>& bytes,
                                   const std::vector<std::string>& paths) {
  return definition.ReadNumbers(bytes.data(), bytes.size(), paths);
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// turtlebot3_msgs/msg/SensorState as rosbag2 stores it.
const std::string kTurtlebotSensorState =
    "########################################\n"
    "# CONSTANTS\n"
    "########################################\n"
    "# Bumper states (states are combined, when multiple bumpers are pressed)\n"
    "uint8 BUMPER_FORWARD  = 1\n"
    "uint8 BUMPER_BACKWARD = 2\n"
    "\n"
    "uint8 CLIFF = 1\n"
    "uint8 SONAR = 1\n"
    "uint8 ILLUMINATION = 1\n"
    "uint8 BUTTON0 = 1\n"
    "uint8 BUTTON1 = 2\n"
    "uint8 ERROR_LEFT_MOTOR = 1\n"
    "uint8 ERROR_RIGHT_MOTOR = 2\n"
    "uint8 TORQUE_ON = 1\n"
    "uint8 TORQUE_OFF = 2\n"
    "\n"
    "########################################\n"
    "# Messages\n"
    "########################################\n"
    "std_msgs/Header header\n"
    "\n"
    "uint8 bumper\n"
    "float32 cliff\n"
    "float32 sonar\n"
    "float32 illumination\n"
    "uint8 led\n"
    "uint8 button\n"
    "bool torque\n"
    "int32 left_encoder    # (-2,147,483,648 ~ 2,147,483,647)\n"
    "int32 right_encoder   # (-2,147,483,648 ~ 2,147,483,647)\n"
    "float32 battery" +
    kSeparator +
    "MSG: std_msgs/Header\n"
    "# Standard metadata for higher-level stamped data types.\n"
    "\n"
    "# Two-integer timestamp that is expressed as seconds and nanoseconds.\n"
    "builtin_interfaces/Time stamp\n"
    "\n"
    "# Transform frame with which this data is associated.\n"
    "string frame_id\n" +
    kSeparator +
    "MSG: builtin_interfaces/Time\n"
    "# This message communicates ROS Time defined here:\n"
    "int32 sec\n"
    "\n"
    "# The nanoseconds component, valid in the range [0, 1e9).\n"
    "uint32 nanosec\n";

std::vector<uint8_t> TurtlebotMessage(bool little_endian) {
  Writer w = Writer::Cdr(little_endian);
  w.Put<int32_t>(1700000000).Put<uint32_t>(123456789).String("base_link");
  w.Put<uint8_t>(1).Put<float>(0.5f).Put<float>(1.25f).Put<float>(2.0f);
  w.Put<uint8_t>(3).Put<uint8_t>(2).Put<uint8_t>(1);
  w.Put<int32_t>(-123456).Put<int32_t>(2000000000).Put<float>(12.1f);
  return w.bytes();
}

TEST(MessageDefinitionTest, ReadsTurtlebot3SensorStateFromCdrOfEitherByteOrder) {
  const auto definition = MessageDefinition::Parse("turtlebot3_msgs/msg/SensorState",
                                                   kTurtlebotSensorState, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  EXPECT_EQ("turtlebot3_msgs/SensorState", definition->type());
  EXPECT_TRUE(definition->has_header());
  for (const bool little_endian : {true, false}) {
    SCOPED_TRACE(little_endian ? "little-endian" : "big-endian");
    const auto values = Read(*definition, TurtlebotMessage(little_endian),
                             {"left_encoder", "right_encoder", "header.stamp", "battery"});
    ASSERT_TRUE(values.ok()) << values.message();
    ASSERT_EQ(4u, values->size());
    EXPECT_EQ(-123456.0, (*values)[0]);
    EXPECT_EQ(2000000000.0, (*values)[1]);
    EXPECT_EQ(1700000000.0 + 1e-9 * 123456789.0, (*values)[2]);
    EXPECT_EQ(static_cast<double>(12.1f), (*values)[3]);
  }
  const auto type = definition->FieldType("left_encoder");
  ASSERT_TRUE(type.ok()) << type.message();
  EXPECT_EQ("int32", *type);
  EXPECT_EQ("time", definition->FieldType("header.stamp").value());
  EXPECT_EQ("bool", definition->FieldType("torque").value());
  EXPECT_EQ("float32", definition->FieldType("battery").value());
  const std::vector<std::string> expected = {"header.stamp", "bumper",        "cliff",  "sonar",
                                             "illumination", "led",           "button", "torque",
                                             "left_encoder", "right_encoder", "battery"};
  EXPECT_EQ(expected, definition->NumericFields());
}

TEST(MessageDefinitionTest, ReadsTheRestOfTheMessageAndATimeAndItsPartsTogether) {
  const auto definition = MessageDefinition::Parse("turtlebot3_msgs/SensorState",
                                                   kTurtlebotSensorState, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  std::vector<uint8_t> message = TurtlebotMessage(true);
  message.insert(message.end(), {1, 2, 3});  // Trailing bytes are no error.
  const auto values = Read(*definition, message,
                           {"battery", "header.stamp.nanosec", "header.stamp", "header.stamp.sec",
                            "torque", "led", "cliff", "battery", "bumper"});
  ASSERT_TRUE(values.ok()) << values.message();
  const std::vector<double> expected = {static_cast<double>(12.1f),
                                        123456789.0,
                                        1700000000.0 + 1e-9 * 123456789.0,
                                        1700000000.0,
                                        1.0,
                                        3.0,
                                        0.5,
                                        static_cast<double>(12.1f),
                                        1.0};
  EXPECT_EQ(expected, *values);
  EXPECT_EQ("uint32", definition->FieldType("header.stamp.nanosec").value());
}

TEST(MessageDefinitionTest, ResolvedPathsReadManyMessages) {
  const auto definition = MessageDefinition::Parse("turtlebot3_msgs/SensorState",
                                                   kTurtlebotSensorState, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  const auto paths = definition->Resolve({"right_encoder", "left_encoder"});
  ASSERT_TRUE(paths.ok()) << paths.message();
  EXPECT_EQ(2u, paths->size());
  const std::vector<uint8_t> message = TurtlebotMessage(false);
  std::vector<double> values;
  for (int i = 0; i < 100000; ++i) {
    const Status status = definition->ReadNumbers(message.data(), message.size(), *paths, &values);
    ASSERT_TRUE(status.ok()) << status.message();
  }
  EXPECT_EQ((std::vector<double>{2000000000.0, -123456.0}), values);

  const auto other = MessageDefinition::Parse("turtlebot3_msgs/SensorState", kTurtlebotSensorState,
                                              WireFormat::kCdr);
  ASSERT_TRUE(other.ok()) << other.message();
  EXPECT_FALSE(other->ReadNumbers(message.data(), message.size(), *paths, &values).ok());
  const MessageDefinition copy = *definition;
  EXPECT_TRUE(copy.ReadNumbers(message.data(), message.size(), *paths, &values).ok());
}

// kobuki_msgs/SensorState as rosbag stores it.
const std::string kKobukiSensorState =
    "# Kobuki Sensor Data Messages\n"
    "# Bumper states (states are combined, when multiple bumpers are pressed)\n"
    "uint8 BUMPER_RIGHT  = 1\n"
    "uint8 BUMPER_CENTRE = 2\n"
    "uint8 BUMPER_LEFT   = 4\n"
    "uint8 WHEEL_DROP_RIGHT = 1\n"
    "uint8 WHEEL_DROP_LEFT  = 2\n"
    "uint8 DISCHARGING         = 0\n"
    "uint8 DOCKING_CHARGED     = 2\n"
    "uint8 DOCKING_CHARGING    = 6\n"
    "uint8 OVER_CURRENT_LEFT_WHEEL  = 1\n"
    "uint8 OVER_CURRENT_BOTH_WHEELS = 3\n"
    "\n"
    "###### MESSAGE ######\n"
    "\n"
    "Header header\n"
    "\n"
    "###################\n"
    "# Core Packet\n"
    "###################\n"
    "uint16 time_stamp      # milliseconds starting when turning on Kobuki (max. 65536, then "
    "starts from 0 again)\n"
    "uint8  bumper          # see bumper states\n"
    "uint8  wheel_drop      # see wheel drop sensor states\n"
    "uint8  cliff           # see cliff sensor states\n"
    "uint16 left_encoder    # accumulated ticks left wheel starting with turning on Kobuki (max. "
    "65535)\n"
    "uint16 right_encoder   # accumulated ticks right wheel starting with turning on Kobuki "
    "(max. 65535)\n"
    "int8   left_pwm        # % applied PWM to the left wheel motor (0-100)\n"
    "int8   right_pwm       # % applied PWM to the right wheel motor (0-100)\n"
    "uint8  buttons         # see button states\n"
    "uint8  charger         # see charger states\n"
    "uint8  battery         # battery voltage in 0.1V (ex. 16.1V -> 161)\n"
    "\n"
    "###################\n"
    "# Cliff Packet\n"
    "###################\n"
    "uint16[] bottom        # ADC output of the right, central and left cliff PSD sensor\n"
    "\n"
    "###################\n"
    "# Current Packet\n"
    "###################\n"
    "uint8[] current        # motor current for the left and right motor in 10mA (ex. 12 -> "
    "120mA)\n"
    "uint8  over_current    # see overcurrent states\n"
    "\n"
    "###################\n"
    "# GP Input Packet\n"
    "###################\n"
    "uint16 digital_input   # digital input bits 0-3\n"
    "uint16[] analog_input  # ADC output of the analog input ports 0-3\n" +
    kSeparator +
    "MSG: std_msgs/Header\n"
    "# Standard metadata for higher-level stamped data types.\n"
    "# sequence ID: consecutively increasing ID \n"
    "uint32 seq\n"
    "#Two-integer timestamp that is expressed as:\n"
    "time stamp\n"
    "#Frame this data is associated with\n"
    "string frame_id\n";

Writer KobukiMessage(uint32_t bottom_count = 3) {
  Writer w = Writer::Ros1();
  w.Put<uint32_t>(7).Put<uint32_t>(1600000000).Put<uint32_t>(500000000).String("base_footprint");
  w.Put<uint16_t>(40000).Put<uint8_t>(0).Put<uint8_t>(0).Put<uint8_t>(0);
  w.Put<uint16_t>(65000).Put<uint16_t>(33000).Put<int8_t>(-5).Put<int8_t>(7);
  w.Put<uint8_t>(0).Put<uint8_t>(6).Put<uint8_t>(160);
  w.Put<uint32_t>(bottom_count).Put<uint16_t>(100).Put<uint16_t>(200).Put<uint16_t>(300);
  w.Put<uint32_t>(2).Put<uint8_t>(1).Put<uint8_t>(2);
  w.Put<uint8_t>(0).Put<uint16_t>(0xBEEF);
  w.Put<uint32_t>(4).Put<uint16_t>(1).Put<uint16_t>(2).Put<uint16_t>(3).Put<uint16_t>(4);
  return w;
}

TEST(MessageDefinitionTest, ReadsKobukiSensorStateFromRos1PastItsVariableArrays) {
  const auto definition =
      MessageDefinition::Parse("kobuki_msgs/SensorState", kKobukiSensorState, WireFormat::kRos1);
  ASSERT_TRUE(definition.ok()) << definition.message();
  EXPECT_TRUE(definition->has_header());
  const auto values = Read(*definition, KobukiMessage().bytes(),
                           {"digital_input", "left_encoder", "right_encoder", "left_pwm",
                            "header.stamp", "header.seq", "time_stamp", "battery", "over_current"});
  ASSERT_TRUE(values.ok()) << values.message();
  const std::vector<double> expected = {
      48879.0, 65000.0, 33000.0, -5.0, 1600000000.0 + 1e-9 * 500000000.0, 7.0, 40000.0, 160.0, 0.0};
  EXPECT_EQ(expected, *values);
  EXPECT_EQ("uint16", definition->FieldType("left_encoder").value());
  EXPECT_EQ("int8", definition->FieldType("right_pwm").value());
  EXPECT_EQ("time", definition->FieldType("header.stamp").value());
  const std::vector<std::string> numeric = {
      "header.seq", "header.stamp", "time_stamp",    "bumper",       "wheel_drop",
      "cliff",      "left_encoder", "right_encoder", "left_pwm",     "right_pwm",
      "buttons",    "charger",      "battery",       "over_current", "digital_input"};
  EXPECT_EQ(numeric, definition->NumericFields());
}

TEST(MessageDefinitionTest, ReadsNestedFieldsPastFixedArraysInBothFormats) {
  const std::string text =
      "geometry_msgs/Vector3 v\n"
      "float64[3] xyz\n"
      "Inner inner  # Same package: my_pkg/Inner.\n"
      "string[2] names\n"
      "Inner[] inners\n"
      "Nothing nothing\n"
      "int64 wanted\n"
      "Inner[2] pair\n"
      "uint8 last" +
      kSeparator + "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z" + kSeparator +
      "MSG: my_pkg/Inner\nuint8 flag\nfloat32 left\n" + kSeparator + "MSG: my_pkg/Nothing\n";
  for (const WireFormat format : {WireFormat::kRos1, WireFormat::kCdr}) {
    for (const bool little_endian : {true, false}) {
      if (format == WireFormat::kRos1 && !little_endian) continue;
      const bool cdr = format == WireFormat::kCdr;
      SCOPED_TRACE(std::string(cdr ? "CDR " : "ROS 1 ") + (little_endian ? "LE" : "BE"));
      const auto definition = MessageDefinition::Parse("my_pkg/Custom", text, format);
      ASSERT_TRUE(definition.ok()) << definition.message();
      EXPECT_FALSE(definition->has_header());
      Writer w = cdr ? Writer::Cdr(little_endian) : Writer::Ros1();
      w.Put<double>(1.5).Put<double>(-2.5).Put<double>(3.5);
      w.Put<double>(10).Put<double>(11).Put<double>(12);
      w.Put<uint8_t>(9).Put<float>(0.25f);
      w.String("left").String("right");
      w.Put<uint32_t>(2).Put<uint8_t>(1).Put<float>(1.f).Put<uint8_t>(2).Put<float>(2.f);
      if (cdr) w.Put<uint8_t>(0);  // ROS 2's member of an empty message.
      w.Put<int64_t>(-(int64_t{1} << 40));
      w.Put<uint8_t>(3).Put<float>(3.f).Put<uint8_t>(4).Put<float>(4.f);
      w.Put<uint8_t>(200);
      const auto values =
          Read(*definition, w.bytes(), {"wanted", "v.y", "inner.left", "inner.flag", "last"});
      ASSERT_TRUE(values.ok()) << values.message();
      const std::vector<double> expected = {-1099511627776.0, -2.5, 0.25, 9.0, 200.0};
      EXPECT_EQ(expected, *values);
    }
  }
  const auto definition = MessageDefinition::Parse("my_pkg/Custom", text, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  const std::vector<std::string> numeric = {"v.x",        "v.y",    "v.z", "inner.flag",
                                            "inner.left", "wanted", "last"};
  EXPECT_EQ(numeric, definition->NumericFields());
  const auto xyz = definition->FieldType("xyz");
  ASSERT_FALSE(xyz.ok());
  EXPECT_TRUE(Contains(xyz.message(), "array")) << xyz.message();
  const auto inside_array = definition->FieldType("inners.flag");
  ASSERT_FALSE(inside_array.ok());
  EXPECT_TRUE(Contains(inside_array.message(), "inside arrays")) << inside_array.message();
  const auto message = definition->FieldType("v");
  ASSERT_FALSE(message.ok());
  EXPECT_TRUE(Contains(message.message(), "v.x, v.y, v.z")) << message.message();
}

TEST(MessageDefinitionTest, ReadsRos2BoundedTypesDefaultsAndBytes) {
  const std::string text =
      "string<=8 name\n"
      "int16[<=4] values\n"
      "uint8[2] pair\n"
      "byte b\n"
      "char c\n"
      "float32 x 1.5      # A default value.\n"
      "string s \"a # b\"  # A default string.\n"
      "int32 FOO=3\n"
      "int32 BAR = 4\n"
      "string NAME=\"x\"\n"
      "builtin_interfaces/Duration period  # Built in when the text leaves it out.\n"
      "uint32 ticks\n";
  const auto definition = MessageDefinition::Parse("my_pkg/Bounded", text, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  Writer w = Writer::Cdr(true);
  w.String("abc").Put<uint32_t>(3).Put<int16_t>(-1).Put<int16_t>(2).Put<int16_t>(3);
  w.Put<uint8_t>(5).Put<uint8_t>(6).Put<uint8_t>(0xF0).Put<uint8_t>('A').Put<float>(7.5f);
  w.String("a # b").Put<int32_t>(-2).Put<uint32_t>(250000000).Put<uint32_t>(4000000000u);
  const auto values = Read(*definition, w.bytes(), {"ticks", "b", "c", "x", "period"});
  ASSERT_TRUE(values.ok()) << values.message();
  EXPECT_EQ((std::vector<double>{4000000000.0, 240.0, 65.0, 7.5, -2.0 + 1e-9 * 250000000.0}),
            *values);
  EXPECT_EQ("uint8", definition->FieldType("b").value());
  EXPECT_EQ("duration", definition->FieldType("period").value());
  EXPECT_EQ((std::vector<std::string>{"b", "c", "x", "period", "ticks"}),
            definition->NumericFields());
}

TEST(MessageDefinitionTest, Ros1ByteIsSignedAndCharUnsigned) {
  const auto definition =
      MessageDefinition::Parse("my_pkg/Bytes", "byte b\nchar c\nduration d\n", WireFormat::kRos1);
  ASSERT_TRUE(definition.ok()) << definition.message();
  Writer w = Writer::Ros1();
  w.Put<uint8_t>(0xF0).Put<uint8_t>(0xF0).Put<int32_t>(-3).Put<int32_t>(-500000000);
  const auto values = Read(*definition, w.bytes(), {"b", "c", "d"});
  ASSERT_TRUE(values.ok()) << values.message();
  EXPECT_EQ((std::vector<double>{-16.0, 240.0, -3.0 + 1e-9 * -500000000.0}), *values);
  EXPECT_EQ("int8", definition->FieldType("b").value());
}

TEST(MessageDefinitionTest, AnUnknownPathListsTheNumericFields) {
  const auto definition = MessageDefinition::Parse("turtlebot3_msgs/SensorState",
                                                   kTurtlebotSensorState, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  for (const std::string path : {"left_encoderz", "header.stamp.secs", "bumper.x", "", "header."}) {
    const auto values = Read(*definition, TurtlebotMessage(true), {"left_encoder", path});
    ASSERT_FALSE(values.ok()) << path;
    EXPECT_EQ(StatusCode::kInvalidInput, values.code());
    EXPECT_TRUE(Contains(values.message(), "no field '" + path +
                                               "' in turtlebot3_msgs/SensorState; its numeric " +
                                               "fields: header.stamp, bumper, cliff,"))
        << values.message();
    EXPECT_TRUE(Contains(values.message(), "left_encoder, right_encoder, battery"))
        << values.message();
  }
}

TEST(MessageDefinitionTest, APathToAStringOrAnArrayIsNoNumber) {
  const auto turtlebot = MessageDefinition::Parse("turtlebot3_msgs/SensorState",
                                                  kTurtlebotSensorState, WireFormat::kCdr);
  ASSERT_TRUE(turtlebot.ok()) << turtlebot.message();
  const auto frame = Read(*turtlebot, TurtlebotMessage(true), {"header.frame_id"});
  ASSERT_FALSE(frame.ok());
  EXPECT_TRUE(Contains(frame.message(), "'header.frame_id'")) << frame.message();
  EXPECT_TRUE(Contains(frame.message(), "string, not a number")) << frame.message();
  EXPECT_FALSE(turtlebot->FieldType("header.frame_id").ok());

  const auto kobuki =
      MessageDefinition::Parse("kobuki_msgs/SensorState", kKobukiSensorState, WireFormat::kRos1);
  ASSERT_TRUE(kobuki.ok()) << kobuki.message();
  const auto bottom = Read(*kobuki, KobukiMessage().bytes(), {"bottom"});
  ASSERT_FALSE(bottom.ok());
  EXPECT_TRUE(Contains(bottom.message(), "'bottom'")) << bottom.message();
  EXPECT_TRUE(Contains(bottom.message(), "array")) << bottom.message();
}

TEST(MessageDefinitionTest, EveryPrefixOfAMessageEndsInsideAField) {
  const auto turtlebot = MessageDefinition::Parse("turtlebot3_msgs/SensorState",
                                                  kTurtlebotSensorState, WireFormat::kCdr);
  ASSERT_TRUE(turtlebot.ok()) << turtlebot.message();
  const std::vector<uint8_t> cdr = TurtlebotMessage(false);
  for (size_t n = 0; n < cdr.size(); ++n) {
    const auto values = turtlebot->ReadNumbers(cdr.data(), n, {"left_encoder", "battery"});
    ASSERT_FALSE(values.ok()) << n;
    EXPECT_EQ(StatusCode::kInvalidInput, values.code());
    EXPECT_TRUE(Contains(values.message(), n < 4 ? "end inside the CDR encapsulation header"
                                                 : "the message's " + std::to_string(n) +
                                                       " bytes end inside field '"))
        << values.message();
  }
  EXPECT_TRUE(
      Contains(turtlebot->ReadNumbers(cdr.data(), 14, {"battery"}).message(), "'header.frame_id'"));
  EXPECT_TRUE(turtlebot->ReadNumbers(cdr.data(), cdr.size(), {"battery"}).ok());

  const auto kobuki =
      MessageDefinition::Parse("kobuki_msgs/SensorState", kKobukiSensorState, WireFormat::kRos1);
  ASSERT_TRUE(kobuki.ok()) << kobuki.message();
  const std::vector<uint8_t> ros1 = KobukiMessage().bytes();
  const size_t digital_input_end = ros1.size() - 12;
  for (size_t n = 0; n < digital_input_end; ++n) {
    const auto values = kobuki->ReadNumbers(ros1.data(), n, {"digital_input"});
    ASSERT_FALSE(values.ok()) << n;
    EXPECT_TRUE(Contains(values.message(), "bytes end inside field '")) << values.message();
  }
  EXPECT_TRUE(kobuki->ReadNumbers(ros1.data(), digital_input_end, {"digital_input"}).ok());
  // 30 bytes of header, 14 of the core packet, then the bottom count and one of its items.
  EXPECT_TRUE(Contains(kobuki->ReadNumbers(ros1.data(), 50, {"digital_input"}).message(),
                       "the message's 50 bytes end inside field 'bottom'"));
}

TEST(MessageDefinitionTest, AnAbsurdCountFailsWithoutAllocating) {
  const auto kobuki =
      MessageDefinition::Parse("kobuki_msgs/SensorState", kKobukiSensorState, WireFormat::kRos1);
  ASSERT_TRUE(kobuki.ok()) << kobuki.message();
  const auto values = Read(*kobuki, KobukiMessage(0xFFFFFFFF).bytes(), {"digital_input"});
  ASSERT_FALSE(values.ok());
  EXPECT_TRUE(Contains(values.message(), "field 'bottom': it counts 4294967295 items"))
      << values.message();

  // A string's length, a CDR sequence of messages and a huge fixed array.
  const std::string text = "Inner[] inners\nstring s\nuint8[4000000000] big\nuint8 wanted" +
                           kSeparator + "MSG: my_pkg/Inner\nuint8 flag\nfloat32 left\n";
  const auto definition = MessageDefinition::Parse("my_pkg/Custom", text, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  const auto inners = Read(
      *definition, Writer::Cdr(true).Put<uint32_t>(0xFFFFFFFF).Raw({1, 2, 3}).bytes(), {"wanted"});
  ASSERT_FALSE(inners.ok());
  EXPECT_TRUE(Contains(inners.message(), "field 'inners': it counts 4294967295 items"))
      << inners.message();
  const auto string =
      Read(*definition, Writer::Cdr(true).Put<uint32_t>(0).Put<uint32_t>(0xFFFFFFFF).bytes(),
           {"wanted"});
  ASSERT_FALSE(string.ok());
  EXPECT_TRUE(Contains(string.message(), "end inside field 's'")) << string.message();
  const auto big =
      Read(*definition, Writer::Cdr(true).Put<uint32_t>(0).String("x").Raw({1, 2, 3}).bytes(),
           {"wanted"});
  ASSERT_FALSE(big.ok());
  EXPECT_TRUE(Contains(big.message(), "end inside field 'big'")) << big.message();
}

TEST(MessageDefinitionTest, ASyntaxErrorNamesTheTypeAndLine) {
  for (const std::string bad : {"int32[x] a", "int32", "foo-bar baz", "int32 9lives", "int32[<=] a",
                                "string<=x s", "a/b/c/d e"}) {
    const auto definition = MessageDefinition::Parse(
        "my_pkg/Bad", "# A comment.\nint32 ok\n" + bad + "\nint32 fine\n", WireFormat::kRos1);
    ASSERT_FALSE(definition.ok()) << bad;
    EXPECT_EQ(StatusCode::kInvalidInput, definition.code());
    EXPECT_TRUE(
        Contains(definition.message(), "message definition of my_pkg/Bad, line 3 ('" + bad + "')"))
        << definition.message();
  }
  const auto no_msg = MessageDefinition::Parse(
      "my_pkg/Bad", "Inner i" + kSeparator + "uint8 flag\n", WireFormat::kRos1);
  ASSERT_FALSE(no_msg.ok());
  EXPECT_TRUE(Contains(no_msg.message(), "line 3")) << no_msg.message();
  EXPECT_TRUE(Contains(no_msg.message(), "MSG:")) << no_msg.message();
  EXPECT_FALSE(MessageDefinition::Parse("Bad", "int32 a\n", WireFormat::kRos1).ok());
  const auto itself = MessageDefinition::Parse("my_pkg/Loop", "Loop again\n", WireFormat::kCdr);
  ASSERT_FALSE(itself.ok());
  EXPECT_TRUE(Contains(itself.message(), "my_pkg/Loop contains itself")) << itself.message();
}

TEST(MessageDefinitionTest, AMissingDependencyIsNamed) {
  const auto definition = MessageDefinition::Parse(
      "my_pkg/Custom", "uint8 a\ngeometry_msgs/Vector3 v\nfloat64 b\n", WireFormat::kCdr);
  ASSERT_FALSE(definition.ok());
  EXPECT_TRUE(Contains(definition.message(), "line 2")) << definition.message();
  EXPECT_TRUE(Contains(definition.message(), "geometry_msgs/Vector3 of field 'v'"))
      << definition.message();
  EXPECT_TRUE(Contains(definition.message(), "no 'MSG: geometry_msgs/Vector3' section"))
      << definition.message();
  // A ROS 2 bag may name the sections pkg/msg/Type.
  EXPECT_TRUE(MessageDefinition::Parse(
                  "my_pkg/Custom",
                  "uint8 a\ngeometry_msgs/msg/Vector3 v\nfloat64 b" + kSeparator +
                      "MSG: geometry_msgs/msg/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n",
                  WireFormat::kCdr)
                  .ok());
}

TEST(MessageDefinitionTest, AnUnsupportedCdrEncapsulationIsNamed) {
  const auto definition = MessageDefinition::Parse("turtlebot3_msgs/SensorState",
                                                   kTurtlebotSensorState, WireFormat::kCdr);
  ASSERT_TRUE(definition.ok()) << definition.message();
  std::vector<uint8_t> message = TurtlebotMessage(true);
  message[1] = 2;
  const auto values = Read(*definition, message, {"left_encoder"});
  ASSERT_FALSE(values.ok());
  EXPECT_TRUE(Contains(values.message(), "unsupported CDR encapsulation 00 02"))
      << values.message();
}

TEST(MessageDefinitionTest, CorruptMessagesFailCleanly) {
  const auto turtlebot = MessageDefinition::Parse("turtlebot3_msgs/SensorState",
                                                  kTurtlebotSensorState, WireFormat::kCdr);
  const auto kobuki =
      MessageDefinition::Parse("kobuki_msgs/SensorState", kKobukiSensorState, WireFormat::kRos1);
  ASSERT_TRUE(turtlebot.ok()) << turtlebot.message();
  ASSERT_TRUE(kobuki.ok()) << kobuki.message();
  std::mt19937 random(7);
  for (int trial = 0; trial < 2000; ++trial) {
    const bool cdr = trial % 2 == 0;
    const MessageDefinition& definition = cdr ? *turtlebot : *kobuki;
    std::vector<uint8_t> message = cdr ? TurtlebotMessage(trial % 4 == 0) : KobukiMessage().bytes();
    for (int i = 0; i < 3; ++i) message[random() % message.size()] = static_cast<uint8_t>(random());
    const auto values = Read(definition, message, definition.NumericFields());
    if (!values.ok()) {
      EXPECT_EQ(StatusCode::kInvalidInput, values.code()) << values.message();
    }
  }
}

}  // namespace
}  // namespace calib
