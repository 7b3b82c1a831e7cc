#include <calib/core/csv.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>
#include <string>
#include <system_error>
#include <unordered_map>
#include <utility>

namespace calib {
namespace {

bool IsBlank(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsBlank(s.back())) s.remove_suffix(1);
  return s;
}

std::string Lower(std::string_view s) {
  std::string lower(s);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower;
}

std::string At(const std::string& source, int64_t line) {
  return source + ":" + std::to_string(line) + ": ";
}

}  // namespace

StatusOr<CsvReader> CsvReader::Open(std::string_view text, std::string source,
                                    std::vector<CsvColumn> columns) {
  CsvReader reader;
  reader.text_ = WithoutBom(text);
  reader.source_ = std::move(source);
  reader.columns_ = std::move(columns);
  CALIB_RETURN_IF_ERROR(reader.ReadHeader());
  return reader;
}

StatusOr<bool> CsvReader::NextLine(std::string_view* line, bool header) {
  while (pos_ < text_.size()) {
    // Only kMaxLineBytes + 1 bytes are searched: a line without end costs no more.
    const size_t window = std::min(text_.size() - pos_, kMaxLineBytes + 1);
    const void* newline = std::memchr(text_.data() + pos_, '\n', window);
    ++line_number_;
    if (newline == nullptr && window > kMaxLineBytes) {
      if (header) {
        // A header this long is most likely one of too many columns: say so, counted once.
        const std::string_view rest = text_.substr(pos_, text_.find('\n', pos_) - pos_);
        const size_t columns = static_cast<size_t>(std::count(rest.begin(), rest.end(), ',')) + 1;
        if (columns > kMaxCsvColumns) return TooManyColumns(columns);
      }
      return Status::InvalidInput(At(source_, line_number_) + "line longer than " +
                                  std::to_string(kMaxLineBytes) +
                                  " bytes (the limit of a CSV record): not a log of this format");
    }
    const size_t stop = newline == nullptr
                            ? text_.size()
                            : static_cast<size_t>(static_cast<const char*>(newline) - text_.data());
    *line = Trim(text_.substr(pos_, stop - pos_));
    pos_ = stop + 1;
    if (!line->empty() && line->front() != '#') return true;
  }
  return false;
}

std::string CsvReader::Split(std::string_view line) {
  fields_.clear();
  size_t i = 0;
  while (true) {
    while (i < line.size() && IsBlank(line[i]) && line[i] != ',') ++i;
    const size_t k = fields_.size();
    if (i < line.size() && line[i] == '"') {
      // Quoted: up to the closing quote, "" standing for one quote.
      const size_t open = i++;
      std::string_view field;
      bool escaped = false;
      size_t start = i;
      while (true) {
        const size_t quote = line.find('"', i);
        if (quote == std::string_view::npos) {
          return "field " + std::to_string(k + 1) + ": the quote opened at character " +
                 std::to_string(open + 1) + " is never closed";
        }
        if (quote + 1 < line.size() && line[quote + 1] == '"') {
          escaped = true;
          i = quote + 2;
          continue;
        }
        field = line.substr(start, quote - start);
        i = quote + 1;
        break;
      }
      if (escaped) {
        if (unescaped_.size() <= k) unescaped_.resize(k + 1);
        std::string& out = unescaped_[k];
        out.clear();
        for (size_t j = 0; j < field.size(); ++j) {
          out += field[j];
          if (field[j] == '"') ++j;  // Skip the second quote of "".
        }
        field = out;
      }
      while (i < line.size() && IsBlank(line[i])) ++i;
      if (i < line.size() && line[i] != ',') {
        return "field " + std::to_string(k + 1) + ": unexpected '" + std::string(1, line[i]) +
               "' after the closing quote (expected ',' or the line's end)";
      }
      fields_.push_back(field);
    } else {
      const size_t comma = line.find(',', i);
      const size_t stop = comma == std::string_view::npos ? line.size() : comma;
      const std::string_view field = Trim(line.substr(i, stop - i));
      fields_.push_back(field);
      i = stop;
    }
    if (i >= line.size()) break;
    ++i;  // The comma.
  }
  return std::string();
}

Status CsvReader::TooManyColumns(size_t columns) const {
  return Status::InvalidInput(
      At(source_, line_number_) + "the header has " + std::to_string(columns) +
      " columns, more than the " + std::to_string(kMaxCsvColumns) +
      " a CSV log may have (expected a header naming " + RequiredNames() + ")");
}

Status CsvReader::ReadHeader() {
  std::string_view line;
  CALIB_ASSIGN_OR_RETURN(const bool found, NextLine(&line, /*header=*/true));
  if (!found) {
    return Status::InvalidInput(source_ +
                                ": holds no records: no header line (an empty file, or only "
                                "blank and comment lines); expected a header naming " +
                                RequiredNames());
  }
  header_line_ = line_number_;
  // Counted before splitting: a header of a million commas is refused without a million fields.
  const size_t columns = static_cast<size_t>(std::count(line.begin(), line.end(), ',')) + 1;
  if (columns > kMaxCsvColumns) return TooManyColumns(columns);
  if (const std::string problem = Split(line); !problem.empty()) {
    std::string all;
    for (const CsvColumn& column : columns_) {
      if (column.required) all += (all.empty() ? "" : ", ") + std::string(column.name);
    }
    return Status::InvalidInput(At(source_, header_line_) +
                                "the header lacks the required column(s) " + all +
                                ": it is not a CSV header (" + problem + ")");
  }
  num_fields_ = fields_.size();
  // Wanted columns by exact name, and by lower-cased name when that is unambiguous (−1).
  std::unordered_map<std::string, int> exact, folded;
  for (size_t w = 0; w < columns_.size(); ++w) {
    exact.emplace(columns_[w].name, static_cast<int>(w));
    const auto [it, fresh] = folded.emplace(Lower(columns_[w].name), static_cast<int>(w));
    if (!fresh) it->second = -1;
  }
  field_of_.assign(columns_.size(), -1);
  // First header field of each key: "#w" for a wanted column, the lower-cased name otherwise.
  std::unordered_map<std::string, size_t> seen;
  for (size_t i = 0; i < fields_.size(); ++i) {
    const std::string_view name = fields_[i];
    int w = -1;
    if (const auto e = exact.find(std::string(name)); e != exact.end()) {
      w = e->second;
    } else if (const auto f = folded.find(Lower(name)); f != folded.end()) {
      w = f->second;
    }
    const std::string key = w >= 0 ? "#" + std::to_string(w) : Lower(name);
    const auto [it, fresh] = seen.emplace(key, i);
    if (!fresh) {
      return Status::InvalidInput(At(source_, header_line_) + "column '" + std::string(name) +
                                  "' appears twice in the header (duplicated column name: "
                                  "columns " +
                                  std::to_string(it->second + 1) + " and " + std::to_string(i + 1) +
                                  ")");
    }
    if (w >= 0) field_of_[static_cast<size_t>(w)] = static_cast<int>(i);
  }
  std::string missing, listed;
  for (size_t w = 0; w < columns_.size(); ++w) {
    if (field_of_[w] >= 0 || !columns_[w].required) continue;
    missing += (missing.empty() ? "" : ", ") + std::string(columns_[w].name);
    listed += (listed.empty() ? "no column '" : "', no column '") + std::string(columns_[w].name);
  }
  if (!missing.empty()) {
    return Status::InvalidInput(At(source_, header_line_) +
                                "the header lacks the required column(s) " + missing + " (" +
                                listed + "'; a header names at least " + RequiredNames() + ")");
  }
  return Status::Ok();
}

StatusOr<bool> CsvReader::Next() {
  std::string_view line;
  CALIB_ASSIGN_OR_RETURN(const bool found, NextLine(&line));
  if (!found) return false;
  line_ = line_number_;
  ++record_;
  if (const std::string problem = Split(line); !problem.empty()) {
    return Status::InvalidInput(Where() + problem);
  }
  if (fields_.size() != num_fields_) {
    return Status::InvalidInput(Where() + "found " + std::to_string(fields_.size()) +
                                " fields, expected " + std::to_string(num_fields_) +
                                " comma-separated fields (the header has " +
                                std::to_string(num_fields_) + ")");
  }
  return true;
}

std::string_view CsvReader::Field(size_t column) const {
  const int at = field_of_[column];
  return at < 0 ? std::string_view() : fields_[static_cast<size_t>(at)];
}

std::string CsvReader::Where() const {
  return At(source_, line_) + "record " + std::to_string(record_) + ": ";
}

std::string CsvReader::ColumnWhere(size_t column) const {
  return " (column " + std::to_string(field_of_[column] + 1) + " '" + columns_[column].name + "')";
}

std::string CsvReader::RequiredNames() const {
  std::string names;
  for (const CsvColumn& column : columns_) {
    if (column.required) names += (names.empty() ? "" : ",") + std::string(column.name);
  }
  return names;
}

Status CsvReader::Number(size_t column, double* value, bool* present) const {
  if (present != nullptr) *present = false;
  const std::string_view field = Field(column);
  const char* name = columns_[column].name;
  if (field.empty()) {
    if (!columns_[column].required && present != nullptr) return Status::Ok();
    if (!Has(column)) return Status::Ok();
    return Status::InvalidInput(Where() + "empty value for " + name + ColumnWhere(column) + ": '" +
                                name + "' is empty");
  }
  double parsed = 0.0;
  const NumberStatus status = ParseDouble(field, &parsed);
  if (status != NumberStatus::kOk) {
    return Status::InvalidInput(Where() + NumberProblem(status, name, field) + ColumnWhere(column));
  }
  *value = parsed;
  if (present != nullptr) *present = true;
  return Status::Ok();
}

Status CsvReader::Integer(size_t column, int* value, const char* what) const {
  const std::string_view field = Field(column);
  const char* end = field.data() + field.size();
  const auto result = std::from_chars(field.data(), end, *value);
  if (field.empty() || result.ec != std::errc() || result.ptr != end) {
    return Status::InvalidInput(Where() + columns_[column].name + " must be " + what + ", got '" +
                                std::string(field) + "'" + ColumnWhere(column));
  }
  return Status::Ok();
}

}  // namespace calib
