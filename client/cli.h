// What every mapctl subcommand shares: its connection, flag parsing (CLI11), exit
// codes and the one-line error format
//   mapctl: <what failed>: <server message> (<CODE>)
#ifndef MAPD_CLIENT_CLI_H_
#define MAPD_CLIENT_CLI_H_

#include <grpcpp/grpcpp.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "client/robot/robot_client.h"
#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::client {

// Exit codes scripts can rely on.
enum ExitCode : int {
  kExitOk = 0,
  kExitFailed = 1,  // the server answered an error, batches were rejected, or a local file failed
  kExitUsage = 2,   // bad flags, unknown command, malformed input file
  kExitUnreachable = 3,  // the server could not be reached
};

struct Context {
  // host:port; several, comma-separated: instances of one database, tried in
  // turn (servers).
  std::string server;
  std::vector<std::string> servers;  // `server` split at its commas
  double timeout_s = 10;             // RPC deadline; for ingest/simulate the wait for the last acks
  std::string token;                 // bearer token (--token / $MAPD_TOKEN); empty: none
  // The map every call is about (--map / $MAPD_MAP), sent as the mapd-map-id
  // metadata; empty: the server's default map.
  std::string map;
  // The server of `map`: the first of `servers` that answers, or, when
  // several mapd share a database, the one its LocateMap names (settled by
  // the first call about the map).
  mutable std::shared_ptr<grpc::Channel> channel;
  mutable std::unique_ptr<mapserver::v1::MapService::Stub> stub;
  // Makes a channel to another address, with the same credentials.
  std::function<std::shared_ptr<grpc::Channel>(const std::string& address)> connect;

  // What a robot stream of this invocation takes: the token, the map, the
  // wait, and the other instances to fail over to. Settles `channel` first.
  robot::RobotClientOptions RobotOptions() const;

  // A context whose deadline is now + timeout_s, carrying the token and the map.
  // With a map other than "default", the first one first asks the server
  // (ListMaps) whether it serves that map: a server from before maps would
  // ignore the metadata and answer for its only map, so then mapctl prints
  // why and exits (1; 3 when the server cannot be reached).
  std::unique_ptr<grpc::ClientContext> NewCallContext() const;
  // The same without a deadline (uploads, merges, downloads take their time).
  std::unique_ptr<grpc::ClientContext> NewStreamContext() const;
  // A call about the server rather than a map (ListMaps, CreateMap): the
  // deadline and the token, no map and no map check.
  std::unique_ptr<grpc::ClientContext> NewServerCallContext() const;
  std::chrono::milliseconds timeout() const;
  // Points channel and stub at `address` (e.g. the owner a redirect names).
  void Use(const std::string& address) const;

 private:
  // Once: finds the server of the map (LocateMap over `servers`), then with
  // a map other than "default" checks that it serves it (see NewCallContext).
  void PrepareMapOnce() const;
  std::shared_ptr<std::once_flag> map_checked_ = std::make_shared<std::once_flag>();
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

// What a parsed command line asks for: set by the chosen subcommand's
// callback (client/commands.h), run once the connection is set up.
using Action = std::function<int(const Context&)>;

// Binds a subcommand to `run`: returns the options struct its flags fill
// (CLI11 keeps pointers into it, so it lives as long as the app), and makes
// the parse set `*action` to run it when this subcommand is chosen.
template <typename Options>
std::shared_ptr<Options> BindCommand(CLI::App* command, Action* action,
                                     int (*run)(const Context&, const Options&)) {
  auto options = std::make_shared<Options>();
  command->callback([options, action, run] {
    *action = [options, run](const Context& ctx) { return run(ctx, *options); };
  });
  return options;
}

// Parses argv with `app`; on a bad command line prints one line
//   mapctl <command>: <what is wrong, naming the flag> (see 'mapctl <command> --help')
// and returns kExitUsage; --help prints the help of the command asked about and
// returns kExitOk. kContinue when the parse succeeded.
constexpr int kContinue = -1;
// A flag check for a finite number > 0 with a plain message ("wants a number
// > 0, got '0'"); CLI::PositiveNumber would print the range up to DBL_MAX.
CLI::Validator PositiveReal();
// The same for ids: a whole number > 0 ("'abc' is not an id (a whole number > 0)").
CLI::Validator PositiveId();
int ParseCommandLine(CLI::App* app, int argc, const char* const* argv);
// Why `address` is not HOST:PORT with a port in 1..65535 (or a gRPC target
// URI such as unix:/path), or "" if it is: a missing port was a connection
// error after the timeout, not a usage error.
std::string ServerAddressProblem(const std::string& address);

// Whole-string number parsing; false on junk, overflow or a non-finite double.
bool ParseDouble(const std::string& s, double* out);
// Splits on `sep`, keeping empty fields.
std::vector<std::string> Split(const std::string& s, char sep);

// Writes `data` to `path` through a temporary file and a rename, or to stdout
// for "-". False with `*error` set on failure.
bool WriteOutput(const std::string& path, const std::string& data, std::string* error);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_CLI_H_
