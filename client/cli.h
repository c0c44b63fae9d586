// What every mapctl subcommand shares: its connection, flag parsing, exit
// codes and the one-line error format
//   mapctl: <what failed>: <server message> (<CODE>)
#ifndef MAPD_CLIENT_CLI_H_
#define MAPD_CLIENT_CLI_H_

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::client {

// Exit codes scripts can rely on.
enum ExitCode : int {
  kExitOk = 0,
  kExitFailed = 1,       // the server answered an error, batches were rejected, or a local file failed
  kExitUsage = 2,        // bad flags, unknown command, malformed input file
  kExitUnreachable = 3,  // the server could not be reached
};

struct Context {
  std::string server;      // host:port
  double timeout_s = 10;   // RPC deadline; for ingest/simulate the wait for the last acks
  std::string token;       // bearer token (--token / $MAPD_TOKEN); empty: none
  std::shared_ptr<grpc::Channel> channel;
  std::unique_ptr<mapserver::v1::MapService::Stub> stub;

  // A context whose deadline is now + timeout_s, carrying the token.
  std::unique_ptr<grpc::ClientContext> NewCallContext() const;
  // The same without a deadline (uploads, merges, downloads take their time).
  std::unique_ptr<grpc::ClientContext> NewStreamContext() const;
  std::chrono::milliseconds timeout() const;
};

// Prints `mapctl: <what>: <message> (<CODE>)` and returns the exit code for
// `status`: kExitUnreachable when the server could not be reached, else kExitFailed.
int ReportRpcError(const Context& ctx, const std::string& what, const grpc::Status& status);
// Prints `mapctl <command>: <message> (see 'mapctl <command> --help')`; returns kExitUsage.
int UsageError(const std::string& command, const std::string& message);
// Prints `mapctl: <message>` on stderr.
void PrintError(const std::string& message);
// Calls GetStats: 0 when the server answers, else the error's exit code (reported).
int CheckReachable(const Context& ctx, const std::string& what);

// "UNAVAILABLE", "INVALID_ARGUMENT", ...
const char* StatusCodeName(grpc::StatusCode code);

// The flags one command accepts.
struct FlagSpec {
  std::string name;  // "--bbox", "-o"
  bool takes_value = false;
};

// Flags (`--name value`, `--name=value`, `-o value`) and positionals; `--`
// ends the flags and a lone `-` is a positional (stdin).
class Args {
 public:
  // False with `*error` set for an unknown flag or a flag missing its value.
  bool Parse(const std::vector<std::string>& args, const std::vector<FlagSpec>& specs, std::string* error);

  bool Has(const std::string& name) const { return values_.count(name) > 0; }
  std::string Get(const std::string& name, const std::string& fallback = "") const;
  const std::vector<std::string>& positionals() const { return positionals_; }

 private:
  std::map<std::string, std::string> values_;
  std::vector<std::string> positionals_;
};

// Parses a command's arguments; --help and -h are added to `specs`. Returns
// kContinue to go on, or the exit code to end with: 0 after printing `help`
// for --help, kExitUsage (reported) for bad flags.
constexpr int kContinue = -1;
int ParseCommandArgs(const std::string& command, const char* help, const std::vector<std::string>& args,
                     std::vector<FlagSpec> specs, Args* out);

// Whole-string number parsing; false on junk, overflow or a non-finite double.
bool ParseDouble(const std::string& s, double* out);
bool ParseUint(const std::string& s, uint64_t* out);
// Splits on `sep`, keeping empty fields.
std::vector<std::string> Split(const std::string& s, char sep);

// Writes `data` to `path` through a temporary file and a rename, or to stdout
// for "-". False with `*error` set on failure.
bool WriteOutput(const std::string& path, const std::string& data, std::string* error);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_CLI_H_
