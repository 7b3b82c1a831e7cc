#ifndef CALIB_CORE_CSV_H_
#define CALIB_CORE_CSV_H_

#include <calib/core/status.h>

#include <cstdint>
#include <deque>
#include <string>
#include <string_view>
#include <vector>

// The one CSV reader of every log format. The text is a header line naming the columns, then
// one record per line:
// - a UTF-8 byte-order mark is skipped, lines may end in CRLF;
// - blank lines and lines whose first non-blank character is '#' are skipped;
// - fields are trimmed of white space; a field may be quoted ("a, b" with "" for a quote), its
//   inside kept as is (a quoted field ends on its line); a quote inside an unquoted field is
//   an ordinary character;
// - header names are matched to the wanted columns case-insensitively after trimming and
//   unquoting, an exact match first (so that distinct columns such as "T" and "t" stay
//   distinct); other columns are ignored; a name given twice is an error;
// - a line longer than kMaxLineBytes or a header of more than kMaxCsvColumns columns
//   (core/text_file.h) is an error: time and memory stay linear in the input;
// - every error names the file, the 1-based line (and record and column) and what is wrong.
namespace calib {

struct CsvColumn {
  const char* name;
  bool required = true;
};

class CsvReader {
 public:
  // Reads the header of `text` (which must outlive the reader). Fails on a missing header,
  // duplicated names or missing required columns.
  static StatusOr<CsvReader> Open(std::string_view text, std::string source,
                                  std::vector<CsvColumn> columns);

  // Moves to the next record; false at the end of the text. Fails on a malformed record (bad
  // quoting, a field count that differs from the header's).
  StatusOr<bool> Next();

  // Whether wanted column `column` is in the header.
  bool Has(size_t column) const { return field_of_[column] >= 0; }
  // The current record's field of wanted column `column` ("" when the header lacks it).
  std::string_view Field(size_t column) const;
  // A finite double; an empty field is an error for a required column and leaves `*present`
  // false (value untouched) for an optional one.
  Status Number(size_t column, double* value, bool* present = nullptr) const;
  // An integer; `what` says what it is in the message ("an integer run id").
  Status Integer(size_t column, int* value, const char* what = "an integer") const;

  const std::string& source() const { return source_; }
  // Counted in 64 bits; SaturatedInt (core/text_file.h) keeps them in an int field.
  int64_t header_line() const { return header_line_; }
  int64_t line() const { return line_; }      // 1-based line of the current record.
  int64_t record() const { return record_; }  // 1-based number of the current record.
  // "source:line: record n: " for the current record.
  std::string Where() const;
  // The required column names, "run,t,left,right".
  std::string RequiredNames() const;
  // The first byte of the text not yet read (the fields of the current line lie before it).
  const char* position() const { return text_.data() + pos_; }

 private:
  CsvReader() = default;
  // Splits `line` (trimmed, not blank) into fields_, unescaping quoted ones. Returns what is
  // wrong with its quoting ("" when nothing).
  std::string Split(std::string_view line);
  // The next line that is neither blank nor a comment, trimmed, in *line; false at the end. An
  // error for a line longer than kMaxLineBytes.
  StatusOr<bool> NextLine(std::string_view* line, bool header = false);
  Status TooManyColumns(size_t columns) const;
  Status ReadHeader();
  std::string ColumnWhere(size_t column) const;

  std::string_view text_;
  size_t pos_ = 0;
  int64_t line_number_ = 0;
  std::string source_;
  std::vector<CsvColumn> columns_;
  std::vector<int> field_of_;  // Header position of each wanted column (−1: absent).
  size_t num_fields_ = 0;
  int64_t header_line_ = 0;
  int64_t line_ = 0;
  int64_t record_ = 0;
  std::vector<std::string_view> fields_;
  std::deque<std::string> unescaped_;  // Quoted fields with "" escapes (stable on growth).
};

}  // namespace calib

#endif  // CALIB_CORE_CSV_H_
