#include "service/file_modes.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "service/log.h"

namespace mapd::service {
namespace {

std::string Octal(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof(text), "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

// FailedPrecondition when others may write `path`, a warning when they may
// read it. A file that does not exist is fine.
Status CheckFile(const std::string& path, const std::string& what, const char* why_secret) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return Status::Ok();
    return Status::FailedPrecondition(what + " '" + path + "': " + std::strerror(errno));
  }
  if (st.st_mode & (S_IWGRP | S_IWOTH)) {
    return Status::FailedPrecondition(what + " '" + path + "' is writable by " +
                                      (st.st_mode & S_IWOTH ? "everyone" : "its group") +
                                      " (mode " + Octal(st.st_mode) + "): " + why_secret +
                                      ". Make it the owner's only: chmod 600 '" + path +
                                      "' (or chmod go-w to keep it readable)");
  }
  if (st.st_mode & (S_IRGRP | S_IROTH)) {
    Log(LogLevel::kWarn, "file_readable_by_others",
        {{"file", path},
         {"what", what},
         {"mode", Octal(st.st_mode)},
         {"fix", "chmod 600 '" + path + "' unless the group is meant to read it"}});
  }
  return Status::Ok();
}

}  // namespace

Status CheckDatabaseFileModes(const std::string& db) {
  constexpr char kWhy[] = "whoever can write it can add an admin token offline or change the map";
  const std::filesystem::path dir = std::filesystem::path(db).parent_path();
  struct stat st {};
  if (stat(dir.empty() ? "." : dir.c_str(), &st) == 0 && (st.st_mode & S_IWOTH) &&
      !(st.st_mode & S_ISVTX)) {
    return Status::FailedPrecondition(
        "the database's directory '" + dir.string() + "' is writable by everyone (mode " +
        Octal(st.st_mode) + ") without the sticky bit: anyone could replace the database. " +
        "Use a directory of mapd's own (chmod 700), or chmod o-w it");
  }
  for (const char* suffix : {"", "-wal", "-shm"}) {
    MAPD_RETURN_IF_ERROR(CheckFile(db + suffix, "the database", kWhy));
  }
  return Status::Ok();
}

Status CheckSecretFileMode(const std::string& path, const std::string& what) {
  return CheckFile(path, what, "whoever can write it can replace the server's identity");
}

}  // namespace mapd::service
