#include "service/log.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/text_escape.h"

namespace mapd::service {
namespace {

std::atomic<int> g_level{static_cast<int>(LogLevel::kInfo)};
std::atomic<uint32_t> g_rate{0};
std::mutex g_mu;

// Per event name: the current one-second window and what it wrote/suppressed.
struct EventWindow {
  int64_t second = 0;
  uint32_t written = 0;
  uint64_t suppressed = 0;
};
std::mutex g_rate_mu;
std::unordered_map<std::string, EventWindow>* g_windows =
    new std::unordered_map<std::string, EventWindow>();

int64_t NowSecond() {
  return std::chrono::duration_cast<std::chrono::seconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

const char* LevelName(LogLevel l) {
  switch (l) {
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarn:
      return "warn";
    case LogLevel::kError:
      return "error";
  }
  return "info";
}

// logfmt: a value is quoted when it is empty or holds a space, '"', '=' or
// anything EscapeControlChars changes; inside quotes '"' and '\\' are escaped,
// and so is every control character, so that one Log call is one line and no
// value can drive a terminal (issue 43: a session id with a newline forged a
// log line).
void AppendValue(const std::string& v, std::string* out) {
  std::string escaped = EscapeControlChars(v, /*escape_backslash=*/true);
  const bool quote = v.empty() || escaped != v || v.find_first_of(" \"=") != std::string::npos;
  if (!quote) {
    out->append(v);
    return;
  }
  out->push_back('"');
  for (char c : escaped) {
    if (c == '"') out->push_back('\\');
    out->push_back(c);
  }
  out->push_back('"');
}

}  // namespace

void SetLogLevel(LogLevel level) { g_level = static_cast<int>(level); }
void SetLogRateLimit(uint32_t lines) { g_rate = lines; }

namespace {

void Write(LogLevel level, const char* event, std::initializer_list<LogField> fields);

void WriteSuppressed(const std::string& event, uint64_t suppressed) {
  Write(LogLevel::kWarn, "log_suppressed",
        {{"of", event}, {"suppressed", std::to_string(suppressed)}, {"window_s", "1"}});
}

// True when the line may be written; collects the summaries of windows that
// are over into `summaries`.
bool Admit(const char* event, std::vector<std::pair<std::string, uint64_t>>* summaries) {
  const uint32_t rate = g_rate.load();
  if (rate == 0) return true;
  const int64_t now = NowSecond();
  std::lock_guard<std::mutex> lock(g_rate_mu);
  EventWindow& w = (*g_windows)[event];
  if (w.second != now) {
    if (w.suppressed > 0) summaries->emplace_back(event, w.suppressed);
    w = EventWindow{now, 0, 0};
  }
  if (w.written < rate) {
    ++w.written;
    return true;
  }
  ++w.suppressed;
  return false;
}

}  // namespace

void FlushSuppressedLogs() {
  std::vector<std::pair<std::string, uint64_t>> summaries;
  {
    const int64_t now = NowSecond();
    std::lock_guard<std::mutex> lock(g_rate_mu);
    for (auto it = g_windows->begin(); it != g_windows->end();) {
      if (it->second.second != now) {
        if (it->second.suppressed > 0) summaries.emplace_back(it->first, it->second.suppressed);
        it = g_windows->erase(it);  // also keeps the map small
      } else {
        ++it;
      }
    }
  }
  for (const auto& [event, n] : summaries) WriteSuppressed(event, n);
}

void Log(LogLevel level, const char* event, std::initializer_list<LogField> fields) {
  if (static_cast<int>(level) < g_level.load()) return;
  std::vector<std::pair<std::string, uint64_t>> summaries;
  const bool admitted = Admit(event, &summaries);
  for (const auto& [e, n] : summaries) WriteSuppressed(e, n);
  if (admitted) Write(level, event, fields);
}

namespace {

void Write(LogLevel level, const char* event, std::initializer_list<LogField> fields) {
  const auto now = std::chrono::system_clock::now();
  const std::time_t secs = std::chrono::system_clock::to_time_t(now);
  const long ms = static_cast<long>(
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char ts[64];
  std::snprintf(ts, sizeof(ts), "%04d-%02d-%02dT%02d:%02d:%02d.%03ldZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, ms);
  std::string line = std::string("ts=") + ts + " level=" + LevelName(level) + " event=" + event;
  for (const auto& [key, value] : fields) {
    line += ' ';
    line += key;
    line += '=';
    AppendValue(value, &line);
  }
  line += '\n';
  std::lock_guard<std::mutex> lock(g_mu);
  std::fputs(line.c_str(), stderr);
}

}  // namespace

}  // namespace mapd::service
