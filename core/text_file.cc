#include <calib/core/text_file.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

namespace calib {

namespace fs = std::filesystem;

Status ReadWholeFile(const std::string& path, std::string* text) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return Status::Io(path + ": no such file");
  if (fs::is_directory(status)) return Status::Io(path + ": is a directory, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Io(path + ": cannot open for reading");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) return Status::Io(path + ": cannot read");
  in.seekg(0, std::ios::beg);
  text->resize(static_cast<size_t>(size));
  if (size > 0 && !in.read(text->data(), size)) return Status::Io(path + ": cannot read");
  return Status::Ok();
}

Status WriteWholeFile(const std::string& path, const std::string& text) {
  // errno says why (no such folder, no space left on device, ...), when the system set it.
  const auto why = [] { return errno != 0 ? std::string(" (") + std::strerror(errno) + ")" : ""; };
  errno = 0;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Status::Io(path + ": cannot open for writing" + why());
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) return Status::Io(path + ": write failed" + why());
  return Status::Ok();
}

}  // namespace calib
