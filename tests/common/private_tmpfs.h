// A small tmpfs for fault tests (a disk that fills up, a read-only mount),
// mounted in a mount namespace private to the test process: the test and the
// mapd it starts see it, the rest of the machine does not, and nothing
// outlives the test. Needs root (CAP_SYS_ADMIN) and a single-threaded process
// at construction (make it before any gRPC channel); else available() is
// false and the test should skip. Header-only.
#ifndef MAPD_TESTS_COMMON_PRIVATE_TMPFS_H_
#define MAPD_TESTS_COMMON_PRIVATE_TMPFS_H_

#include <sched.h>
#include <sys/mount.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace mapd::testing {

class PrivateTmpfs {
 public:
  PrivateTmpfs(const std::string& dir, size_t bytes) : dir_(dir) {
    mkdir(dir.c_str(), 0755);
    static const bool private_namespace =
        unshare(CLONE_NEWNS) == 0 &&
        mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) == 0;
    if (!private_namespace) {
      error_ = std::string("no private mount namespace: ") + std::strerror(errno);
      return;
    }
    if (mount("tmpfs", dir.c_str(), "tmpfs", 0, Options(bytes).c_str()) != 0) {
      error_ = std::string("mount tmpfs: ") + std::strerror(errno);
      return;
    }
    mounted_ = true;
  }
  ~PrivateTmpfs() {
    if (mounted_) umount2(dir_.c_str(), MNT_DETACH);
  }
  PrivateTmpfs(const PrivateTmpfs&) = delete;
  PrivateTmpfs& operator=(const PrivateTmpfs&) = delete;

  bool available() const { return mounted_; }
  const std::string& error() const { return error_; }
  std::string File(const std::string& name) const { return dir_ + "/" + name; }

  // Grows or shrinks the file system (existing files stay).
  bool Resize(size_t bytes) {
    return mount("tmpfs", dir_.c_str(), "tmpfs", MS_REMOUNT, Options(bytes).c_str()) == 0;
  }
  bool SetReadOnly() {
    return mount("tmpfs", dir_.c_str(), "tmpfs", MS_REMOUNT | MS_RDONLY, nullptr) == 0;
  }

 private:
  static std::string Options(size_t bytes) {
    return "size=" + std::to_string(bytes) + ",mode=0755";
  }

  std::string dir_;
  std::string error_;
  bool mounted_ = false;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_PRIVATE_TMPFS_H_
