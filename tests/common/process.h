// Child processes for end-to-end tests: start a real mapd on a free loopback
// port, run a command capturing its output and exit code, stop a process with
// a signal. POSIX only; header-only so any test binary can include it.
//
//   mapd::testing::MapdProcess mapd = mapd::testing::StartMapd(dir.File("map.db"));
//   ASSERT_GT(mapd.port, 0) << mapd.log();
//   auto r = mapd::testing::RunCommand({MAPCTL_BINARY, "--server", mapd.address, "status"});
//   EXPECT_EQ(r.exit_code, 0) << r.err;
//   EXPECT_EQ(mapd::testing::Stop(mapd.pid, SIGTERM), 0);
#ifndef MAPD_TESTS_COMMON_PROCESS_H_
#define MAPD_TESTS_COMMON_PROCESS_H_

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace mapd::testing {

#ifdef MAPD_BINARY
inline constexpr const char* kDefaultMapdBinary = MAPD_BINARY;
#else
inline constexpr const char* kDefaultMapdBinary = "mapd";
#endif

// An exit status as a shell shows it: the exit code, or 128 + signal number.
inline int DecodeWaitStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

namespace internal {

// fork + execve(argv) with the child's stdin/stdout/stderr on the given fds
// (-1: /dev/null), in this process's environment plus `extra_env`
// ("NAME=value" each). Returns the pid, or -1.
inline pid_t Spawn(const std::vector<std::string>& argv, int in_fd, int out_fd, int err_fd,
                   const std::vector<std::string>& extra_env = {}) {
  std::vector<char*> cargv;
  for (const std::string& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  std::vector<char*> cenv;  // built before fork: the child may only make async-signal-safe calls
  for (char** e = environ; *e != nullptr; ++e) cenv.push_back(*e);
  for (const std::string& e : extra_env) cenv.push_back(const_cast<char*>(e.c_str()));
  cenv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid != 0) return pid;
  // Child: only async-signal-safe calls from here on.
  const int null_fd = open("/dev/null", O_RDWR);
  dup2(in_fd >= 0 ? in_fd : null_fd, STDIN_FILENO);
  dup2(out_fd >= 0 ? out_fd : null_fd, STDOUT_FILENO);
  dup2(err_fd >= 0 ? err_fd : null_fd, STDERR_FILENO);
  execve(cargv[0], cargv.data(), cenv.data());
  _exit(127);
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace internal

struct MapdProcess {
  pid_t pid = -1;
  int port = 0;          // 0 if it did not come up
  std::string address;   // "127.0.0.1:PORT"
  std::string log_path;  // its stderr
  std::string log() const { return internal::ReadFile(log_path); }
};

// Starts `binary --db db_path --listen 127.0.0.1:0 extra_args...` with stderr
// in `log_path` (default `db_path + ".log"`) and waits (up to `timeout`) for its
// `event=<ready_event> address=HOST:PORT` line: "serving" (the map is
// recovered, the default) or "listening" (the port is open). On failure port
// is 0 and the child, if still running, is killed. `extra_env` ("NAME=value")
// is added to the environment it inherits.
inline MapdProcess StartMapd(const std::string& db_path,
                             const std::vector<std::string>& extra_args = {},
                             const std::string& binary = kDefaultMapdBinary,
                             std::chrono::milliseconds timeout = std::chrono::seconds(20),
                             const std::string& ready_event = "serving",
                             const std::string& log_path = "",
                             const std::vector<std::string>& extra_env = {}) {
  MapdProcess p;
  p.log_path = log_path.empty() ? db_path + ".log" : log_path;
  std::vector<std::string> argv = {binary, "--db", db_path, "--listen", "127.0.0.1:0"};
  argv.insert(argv.end(), extra_args.begin(), extra_args.end());
  const int log_fd = open(p.log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) return p;
  p.pid = internal::Spawn(argv, -1, log_fd, log_fd, extra_env);
  close(log_fd);
  if (p.pid < 0) return p;

  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const std::string marker = "event=" + ready_event + " address=";
  while (std::chrono::steady_clock::now() < deadline) {
    const std::string log = internal::ReadFile(p.log_path);
    const size_t at = log.find(marker);
    if (at != std::string::npos) {
      const size_t start = at + marker.size();
      const size_t end = log.find_first_of(" \n", start);
      if (end != std::string::npos) {
        p.address = log.substr(start, end - start);
        p.port = std::atoi(p.address.substr(p.address.rfind(':') + 1).c_str());
        return p;
      }
    }
    int status = 0;
    if (waitpid(p.pid, &status, WNOHANG) == p.pid) {  // it exited: bad flags, db error...
      p.pid = -1;
      return p;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(p.pid, SIGKILL);
  waitpid(p.pid, nullptr, 0);
  p.pid = -1;
  return p;
}

struct CommandResult {
  int exit_code = -1;  // as DecodeWaitStatus; -1 if it could not run or timed out
  std::string out;     // stdout
  std::string err;     // stderr
};

// Runs argv[0] (a path, no PATH lookup) with `stdin_data` on its stdin,
// capturing stdout and stderr. Kills it after `timeout`.
inline CommandResult RunCommand(const std::vector<std::string>& argv,
                                const std::string& stdin_data = "",
                                std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  CommandResult r;
  std::signal(SIGPIPE, SIG_IGN);  // a child that exits early must not kill the test
  int in_pipe[2], out_pipe[2], err_pipe[2];
  if (pipe2(in_pipe, O_CLOEXEC) != 0) return r;
  if (pipe2(out_pipe, O_CLOEXEC) != 0 || pipe2(err_pipe, O_CLOEXEC) != 0) return r;
  const pid_t pid = internal::Spawn(argv, in_pipe[0], out_pipe[1], err_pipe[1]);
  close(in_pipe[0]);
  close(out_pipe[1]);
  close(err_pipe[1]);
  if (pid < 0) {
    close(in_pipe[1]);
    close(out_pipe[0]);
    close(err_pipe[0]);
    return r;
  }
  // Feed stdin and drain both outputs together, so no pipe fills up.
  size_t written = 0;
  int in_fd = in_pipe[1];
  if (stdin_data.empty()) {
    close(in_fd);
    in_fd = -1;
  } else {
    fcntl(in_fd, F_SETFL, O_NONBLOCK);
  }
  bool out_open = true, err_open = true, timed_out = false;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  char buf[65536];
  while (out_open || err_open) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      kill(pid, SIGKILL);
      break;
    }
    pollfd fds[3] = {{out_open ? out_pipe[0] : -1, POLLIN, 0},
                     {err_open ? err_pipe[0] : -1, POLLIN, 0},
                     {in_fd, POLLOUT, 0}};
    if (poll(fds, 3, static_cast<int>(left.count())) < 0 && errno != EINTR) break;
    for (int k = 0; k < 2; ++k) {
      if (fds[k].revents == 0) continue;
      const ssize_t n = read(fds[k].fd, buf, sizeof(buf));
      if (n > 0) {
        (k == 0 ? r.out : r.err).append(buf, static_cast<size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        (k == 0 ? out_open : err_open) = false;
      }
    }
    if (in_fd >= 0 && fds[2].revents != 0) {
      const ssize_t n = write(in_fd, stdin_data.data() + written, stdin_data.size() - written);
      if (n > 0) written += static_cast<size_t>(n);
      if (n < 0 && errno != EAGAIN && errno != EINTR) written = stdin_data.size();  // reader gone
      if (written == stdin_data.size()) {
        close(in_fd);
        in_fd = -1;
      }
    }
  }
  if (in_fd >= 0) close(in_fd);
  close(out_pipe[0]);
  close(err_pipe[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  r.exit_code = timed_out ? -1 : DecodeWaitStatus(status);
  return r;
}

// Runs `run()` (returning a CommandResult) every 100 ms until `done(result)`
// or `timeout`; returns the last result. For what a server does a moment
// after it says it serves: an instance on PostgreSQL serves its default map
// first and opens the other maps it takes after.
template <typename Run, typename Done>
CommandResult RunUntil(const Run& run, const Done& done,
                       std::chrono::milliseconds timeout = std::chrono::seconds(60)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  CommandResult r = run();
  while (!done(r) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    r = run();
  }
  return r;
}

// Sends `signal` to `pid` and waits for it to exit (SIGKILL after `timeout`).
// Returns its exit status as DecodeWaitStatus (e.g. 0 for a clean exit, 137
// if it had to be killed), or -1 if `pid` is not our child.
// Resident memory of a running process (VmRSS), MiB; 0 if it is gone.
inline double ResidentMiB(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0;
}

// User + system CPU seconds in a /proc/.../stat file (a process's, or a
// task's under /proc/PID/task); 0 if it cannot be read.
inline double CpuSecondsInStat(const std::string& stat_path) {
  std::ifstream in(stat_path);
  std::string s;
  std::getline(in, s);
  const size_t paren = s.rfind(')');
  if (paren == std::string::npos || paren + 2 > s.size()) return 0;
  std::istringstream fields(s.substr(paren + 2));
  std::string f;
  double utime = 0, stime = 0;
  for (int i = 3; fields >> f; ++i) {
    if (i == 14) utime = std::stod(f);
    if (i == 15) {
      stime = std::stod(f);
      break;
    }
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// CPU seconds a process has used so far.
inline double CpuSeconds(pid_t pid) {
  return CpuSecondsInStat("/proc/" + std::to_string(pid) + "/stat");
}

inline int Stop(pid_t pid, int signal = SIGTERM,
                std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  if (pid <= 0) return -1;
  kill(pid, signal);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  for (;;) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) return DecodeWaitStatus(status);
    if (done < 0) return -1;
    if (std::chrono::steady_clock::now() >= deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return DecodeWaitStatus(status);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_PROCESS_H_
