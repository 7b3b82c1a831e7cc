#ifndef CALIB_CORE_TEXT_FILE_H_
#define CALIB_CORE_TEXT_FILE_H_

#include <calib/core/status.h>

#include <string>

namespace calib {

// Reads a whole file in one go (a million-record log is read once, then parsed in memory).
// Messages name the path: "no such file", "is a directory", "cannot read".
Status ReadWholeFile(const std::string& path, std::string* text);

// Writes `text` to `path`, replacing it.
Status WriteWholeFile(const std::string& path, const std::string& text);

}  // namespace calib

#endif  // CALIB_CORE_TEXT_FILE_H_
