// Counters of the gRPC service for /metrics (web/metrics.cc): per method and
// status code the calls handled and their handling time (the names
// go-grpc-prometheus gives them, so that existing dashboards work), batches
// rejected inside Ingest streams (their stream ends OK), refused submap
// uploads, and how long voxel merges compute.
//
// One registry per process, like the Prometheus client libraries' default
// registry: the server's interceptor and the merge runner record into it,
// the web port reads it. Thread-safe.
#ifndef MAPD_SERVICE_RPC_METRICS_H_
#define MAPD_SERVICE_RPC_METRICS_H_

#include <grpcpp/support/server_interceptor.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "service/latency_histogram.h"

namespace mapd::service {

class RpcMetrics {
 public:
  static RpcMetrics& Default();

  // A call to `full_method` ("/package.Service/Method") ended with `code`
  // after `seconds` (from the arrival of its metadata to its status).
  void RecordCall(std::string_view full_method, grpc::StatusCode code, double seconds);
  void RecordRejectedBatch(grpc::StatusCode code);
  void RecordMerge(double seconds);
  // The merge runner's prepared submaps (prepared_submaps.h) now.
  void SetPreparedSubmaps(uint64_t count, uint64_t bytes);
  struct Prepared {
    uint64_t count = 0, bytes = 0;
  };
  Prepared PreparedSubmaps() const;

  struct Method {
    std::string service;  // "mapserver.v1.MapService"
    std::string method;   // "GetStats"
    std::map<grpc::StatusCode, uint64_t> handled;
    HistogramSnapshot handling;
  };
  std::vector<Method> Methods() const;  // ascending by service, method
  std::map<grpc::StatusCode, uint64_t> RejectedBatches() const;
  std::map<grpc::StatusCode, uint64_t> RefusedUploads() const;  // UploadSubmap, code != OK
  HistogramSnapshot MergeSeconds() const { return merges_.Snapshot(); }

  // For grpc::ServerBuilder::experimental().SetInterceptorCreators.
  static std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>
  InterceptorFactory();

 private:
  struct Entry {
    std::map<grpc::StatusCode, uint64_t> handled;
    LatencyHistogram handling;
  };
  mutable std::mutex mu_;
  std::map<std::string, std::unique_ptr<Entry>, std::less<>> methods_;  // GUARDED_BY(mu_)
  std::map<grpc::StatusCode, uint64_t> rejected_batches_;               // GUARDED_BY(mu_)
  LatencyHistogram merges_;
  Prepared prepared_;  // GUARDED_BY(mu_)
};

// "OK", "INVALID_ARGUMENT", ...: the code's name as gRPC spells it.
const char* GrpcCodeName(grpc::StatusCode code);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_RPC_METRICS_H_
