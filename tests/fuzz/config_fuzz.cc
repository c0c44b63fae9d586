// libFuzzer target: mapd's configuration parser on arbitrary file contents
// (LoadConfigFile reads the bytes through an in-memory file, no disk I/O),
// then ServerConfig::Validate as mapd runs it at start; and ApplySetting on
// the first line split at '=' (the path a command-line flag takes).
// Beyond crashes and sanitizer reports, a bug is a refusal without a message
// (the operator must be told which line and setting).
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "service/config.h"

namespace {

// The bytes as a file path that LoadConfigFile can open: a memfd.
class MemFile {
 public:
  MemFile(const std::uint8_t* data, std::size_t size) : fd_(memfd_create("mapd-config-fuzz", 0)) {
    if (fd_ < 0) std::abort();
    for (std::size_t done = 0; done < size;) {
      const ssize_t n = write(fd_, data + done, size - done);
      if (n <= 0) std::abort();
      done += static_cast<std::size_t>(n);
    }
  }
  ~MemFile() { close(fd_); }
  MemFile(const MemFile&) = delete;
  MemFile& operator=(const MemFile&) = delete;
  std::string path() const { return "/proc/self/fd/" + std::to_string(fd_); }

 private:
  int fd_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mapd::service;
  {
    MemFile file(data, size);
    ServerConfig config;
    mapd::Status s = LoadConfigFile(file.path(), &config);
    if (!s.ok() && s.message().empty()) std::abort();
    if (s.ok()) {
      mapd::Status v = config.Validate();
      if (!v.ok() && v.message().empty()) std::abort();
    }
  }
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string line = text.substr(0, text.find('\n'));
  const std::size_t eq = line.find('=');
  ServerConfig config;
  mapd::Status s = eq == std::string::npos
                       ? ApplySetting(line, "", &config)
                       : ApplySetting(line.substr(0, eq), line.substr(eq + 1), &config);
  if (!s.ok() && s.message().empty()) std::abort();
  return 0;
}
