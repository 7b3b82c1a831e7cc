#include <calib/core/csv.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace calib {
namespace {

// Every record of `text` as the fields of the wanted columns.
std::vector<std::vector<std::string>> ReadAll(const std::string& text,
                                              std::vector<CsvColumn> columns,
                                              std::vector<int>* lines = nullptr) {
  const size_t width = columns.size();
  StatusOr<CsvReader> csv = CsvReader::Open(text, "x.csv", std::move(columns));
  EXPECT_TRUE(csv.ok()) << csv.message();
  std::vector<std::vector<std::string>> rows;
  if (!csv.ok()) return rows;
  while (true) {
    const StatusOr<bool> more = csv->Next();
    EXPECT_TRUE(more.ok()) << more.message();
    if (!more.ok() || !*more) break;
    std::vector<std::string> row;
    for (size_t c = 0; c < width; ++c) row.emplace_back(csv->Field(c));
    rows.push_back(row);
    if (lines != nullptr) lines->push_back(csv->line());
  }
  return rows;
}

// The first failure reading `text` with columns a, b (required) and c (optional).
Status FirstError(const std::string& text) {
  StatusOr<CsvReader> csv = CsvReader::Open(text, "bad.csv", {{"a"}, {"b"}, {"c", false}});
  if (!csv.ok()) return csv.status();
  while (true) {
    const StatusOr<bool> more = csv->Next();
    if (!more.ok()) return more.status();
    if (!*more) return Status::Ok();
    double value = 0.0;
    bool present = false;
    for (size_t c = 0; c < 2; ++c) CALIB_RETURN_IF_ERROR(csv->Number(c, &value));
    CALIB_RETURN_IF_ERROR(csv->Number(2, &value, &present));
  }
}

void ExpectError(const Status& status, const std::vector<std::string>& parts) {
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  for (const std::string& part : parts) {
    EXPECT_NE(status.message().find(part), std::string::npos)
        << "message: " << status.message() << "\nlacks: " << part;
  }
}

TEST(CsvTest, BomCrLfCommentsBlankLinesAndTrimming) {
  std::vector<int> lines;
  const auto rows =
      ReadAll("\xEF\xBB\xBF# comment\r\n\r\n a ,\tb\t\r\n 1 , 2\r\n   \r\n  # another\r\n3,4",
              {{"a"}, {"b"}}, &lines);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"1", "2"}));
  EXPECT_EQ(rows[1], (std::vector<std::string>{"3", "4"}));
  EXPECT_EQ(lines, (std::vector<int>{4, 7}));
}

TEST(CsvTest, HeaderMatchingIsCaseInsensitiveButExactFirst) {
  // "T" and "t" are two columns when both are wanted; otherwise case does not matter.
  const auto rows = ReadAll("t, T ,PHI_L,Extra\n1,2,3,4\n", {{"T"}, {"phi_l"}, {"t"}});
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"2", "3", "1"}));
  EXPECT_EQ(ReadAll("RUN,Left\n1,2\n", {{"run"}, {"left"}})[0],
            (std::vector<std::string>{"1", "2"}));
}

TEST(CsvTest, QuotedFields) {
  const auto rows =
      ReadAll("\"a\", \"b, c\" ,d\n\"x \"\"y\"\"\" ,\" 1,2 \",\"\"\n", {{"a"}, {"b, c"}, {"d"}});
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0], (std::vector<std::string>{"x \"y\"", " 1,2 ", ""}));
  // A quote inside an unquoted field is an ordinary character.
  EXPECT_EQ(ReadAll("a,b\nx\"y,2\n", {{"a"}, {"b"}})[0], (std::vector<std::string>{"x\"y", "2"}));
}

TEST(CsvTest, BadQuotingNamesLineAndField) {
  ExpectError(FirstError("a,b\n1,2\n\"3,4\n"),
              {"bad.csv:3:", "record 2", "field 1", "never closed"});
  ExpectError(FirstError("a,b\n1,\"2\"x\n"), {"bad.csv:2:", "field 2", "after the closing quote"});
  ExpectError(FirstError("a,\"b\n1,2\n"), {"bad.csv:1:", "lacks", "never closed"});
}

TEST(CsvTest, HeaderErrors) {
  ExpectError(FirstError(""), {"bad.csv", "holds no records", "empty file", "a,b"});
  ExpectError(FirstError("# only\n\n"), {"bad.csv", "no header line"});
  ExpectError(FirstError("a,b,A\n"), {"bad.csv:1:", "'A'", "twice", "columns 1 and 3"});
  ExpectError(FirstError("a,b,q,Q\n"), {"bad.csv:1:", "'Q'", "duplicated"});
  ExpectError(FirstError("#\nc,x\n"), {"bad.csv:2:", "lacks", "a, b", "no column 'a'"});
}

TEST(CsvTest, DuplicateDetectionIsLinearInTheColumns) {
  std::string header = "a,b";
  for (int i = 0; i < 9000; ++i) header += ",x" + std::to_string(i);
  EXPECT_TRUE(FirstError(header + "\n").ok());
  ExpectError(FirstError(header + ",X8999\n"), {"'X8999'", "columns 9002 and 9003"});
}

TEST(CsvTest, RecordErrorsNameLineRecordAndColumn) {
  ExpectError(FirstError("a,b\n1,2\n\n1\n"),
              {"bad.csv:4:", "record 2", "found 1 fields", "expected 2"});
  ExpectError(FirstError("a,b\n1,x\n"),
              {"bad.csv:2:", "record 1", "b is not a number", "'x'", "column 2 'b'"});
  ExpectError(FirstError("b,a\n1,nan\n"), {"bad.csv:2:", "a must be finite", "column 2 'a'"});
  ExpectError(FirstError("a,b\n1,1e999\n"), {"bad.csv:2:", "out of range"});
  ExpectError(FirstError("a,b\n,2\n"), {"bad.csv:2:", "empty value for a", "'a' is empty"});
  EXPECT_TRUE(FirstError("a,b,c\n1,2,\n+1,-2e-3,3\n").ok());  // Optional c may be empty.
}

TEST(CsvTest, IntegersAndOptionalColumns) {
  StatusOr<CsvReader> csv =
      CsvReader::Open("run,x\n7,1\n1.5,2\n", "r.csv", {{"run"}, {"y", false}});
  ASSERT_TRUE(csv.ok()) << csv.message();
  EXPECT_FALSE(csv->Has(1));
  ASSERT_TRUE(*csv->Next());
  int run = 0;
  ASSERT_TRUE(csv->Integer(0, &run).ok());
  EXPECT_EQ(run, 7);
  double y = -1.0;
  bool present = true;
  ASSERT_TRUE(csv->Number(1, &y, &present).ok());
  EXPECT_FALSE(present);
  EXPECT_EQ(y, -1.0);
  ASSERT_TRUE(*csv->Next());
  ExpectError(csv->Integer(0, &run, "an integer run id"), {"r.csv:3:", "integer run id", "'1.5'"});
}

}  // namespace
}  // namespace calib
