// Structured log lines (logfmt) on stderr:
//   ts=2026-11-23T08:00:00.123Z level=info event=ingest_rejected robot=r1 seq=7 error="..."
#ifndef MAPD_SERVICE_LOG_H_
#define MAPD_SERVICE_LOG_H_

#include <initializer_list>
#include <string>
#include <utility>

namespace mapd::service {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3 };

using LogField = std::pair<const char*, std::string>;

void SetLogLevel(LogLevel level);
void Log(LogLevel level, const char* event, std::initializer_list<LogField> fields = {});

}  // namespace mapd::service

#endif  // MAPD_SERVICE_LOG_H_
