// Structured log lines (logfmt) on stderr:
//   ts=2026-11-23T08:00:00.123Z level=info event=ingest_rejected robot=r1 seq=7 error="..."
#ifndef MAPD_SERVICE_LOG_H_
#define MAPD_SERVICE_LOG_H_

#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>

namespace mapd::service {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };

using LogField = std::pair<const char*, std::string>;

void SetLogLevel(LogLevel level);
// At most `lines` lines per event name and second (a flood of refused streams
// must not become a flood of log lines); the lines beyond are counted and
// reported as one line per event when its second is over:
//   level=warn event=log_suppressed of=ingest_stream_closed suppressed=9120 window_s=1
// 0 = no limit (the default until mapd sets it).
void SetLogRateLimit(uint32_t lines);
void Log(LogLevel level, const char* event, std::initializer_list<LogField> fields = {});
// Writes the pending log_suppressed lines of seconds that are over (mapd calls
// it every second, so a count is reported even if its event never recurs).
void FlushSuppressedLogs();

}  // namespace mapd::service

#endif  // MAPD_SERVICE_LOG_H_
