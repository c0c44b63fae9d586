#include "web/metrics.h"

#include <dirent.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "service/rpc_metrics.h"
#include "service/watch_hub.h"

namespace mapd::web {
namespace {

// The shortest %g text that reads back as v (0.18, not 0.17999999999999999).
std::string Num(double v) {
  char buf[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

// A bucket bound as written in the bucket list (0.005, 10: the shortest
// fixed-point text that reads back as v), so that a query for le="0.005"
// matches; before, le="0.0050000000000000001".
std::string BoundText(double v) {
  char buf[64];
  for (int decimals = 0; decimals <= 17; ++decimals) {
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    if (std::strtod(buf, nullptr) == v) return buf;
  }
  return Num(v);
}

// What Prometheus's client libraries export as process_* on Linux, from /proc.
struct ProcessSample {
  bool ok = false;
  double cpu_s = 0;
  double rss_bytes = 0;
  double vsize_bytes = 0;
  double start_time_s = 0;  // Unix time
  double open_fds = 0;
  double max_fds = 0;
};

ProcessSample SampleProcess() {
  ProcessSample p;
  std::ifstream stat_file("/proc/self/stat");
  std::string stat((std::istreambuf_iterator<char>(stat_file)), std::istreambuf_iterator<char>());
  // Fields after the command (which may hold spaces), from field 3 (state) on.
  const size_t close = stat.rfind(')');
  if (close == std::string::npos) return p;
  std::istringstream fields(stat.substr(close + 2));
  std::vector<std::string> f;
  for (std::string x; fields >> x;) f.push_back(x);
  if (f.size() < 22) return p;  // f[0] is field 3
  const double ticks = static_cast<double>(sysconf(_SC_CLK_TCK));
  const double page = static_cast<double>(sysconf(_SC_PAGESIZE));
  p.cpu_s = (std::stod(f[11]) + std::stod(f[12])) / ticks;  // utime, stime (fields 14, 15)
  const double start_ticks = std::stod(f[19]);              // starttime (field 22)
  p.vsize_bytes = std::stod(f[20]);                         // field 23
  p.rss_bytes = std::stod(f[21]) * page;                    // field 24, pages
  std::ifstream boot("/proc/stat");
  for (std::string line; std::getline(boot, line);) {
    if (line.rfind("btime ", 0) == 0)
      p.start_time_s = std::stod(line.substr(6)) + start_ticks / ticks;
  }
  if (DIR* dir = opendir("/proc/self/fd"); dir != nullptr) {
    for (dirent* e = readdir(dir); e != nullptr; e = readdir(dir))
      p.open_fds += e->d_name[0] != '.';
    closedir(dir);
    p.open_fds -= 1;  // the directory's own descriptor
  }
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) == 0) p.max_fds = static_cast<double>(limit.rlim_cur);
  p.ok = true;
  return p;
}

class Writer {
 public:
  // One metric family: its HELP and TYPE lines.
  void Family(const char* name, const char* type, const char* help) {
    out_ += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
  }
  void Sample(const std::string& name, double value, const std::string& labels = "") {
    out_ += name + (labels.empty() ? "" : "{" + labels + "}") + " " + Num(value) + "\n";
  }
  // The _bucket, _sum and _count lines of a histogram; `labels` (may be
  // empty) go before le.
  void Histogram(const std::string& name, const service::HistogramSnapshot& h,
                 const std::string& labels = "") {
    const std::string prefix = labels.empty() ? "" : labels + ",";
    for (size_t i = 0; i < h.bounds_s.size(); ++i) {
      Sample(name + "_bucket", static_cast<double>(h.counts[i]),
             prefix + "le=\"" + BoundText(h.bounds_s[i]) + "\"");
    }
    Sample(name + "_bucket", static_cast<double>(h.count), prefix + "le=\"+Inf\"");
    Sample(name + "_sum", h.sum_s, labels);
    Sample(name + "_count", static_cast<double>(h.count), labels);
  }
  std::string& text() { return out_; }

 private:
  std::string out_;
};

// Per-call counters and times (service/rpc_metrics.h), with the names and
// labels of go-grpc-prometheus; batches rejected inside streams, refused
// uploads, merge computation time.
void RpcFamilies(Writer* w) {
  const service::RpcMetrics& rpc = service::RpcMetrics::Default();
  const std::vector<service::RpcMetrics::Method> methods = rpc.Methods();
  const auto labels = [](const service::RpcMetrics::Method& m) {
    return "grpc_service=\"" + m.service + "\",grpc_method=\"" + m.method + "\"";
  };
  w->Family("grpc_server_handled_total", "counter",
            "gRPC calls completed, by method and status code.");
  for (const service::RpcMetrics::Method& m : methods) {
    for (const auto& [code, n] : m.handled) {
      w->Sample("grpc_server_handled_total", static_cast<double>(n),
                labels(m) + ",grpc_code=\"" + service::GrpcCodeName(code) + "\"");
    }
  }
  w->Family("grpc_server_handling_seconds", "histogram",
            "Time from a call's arrival to its status (streams: their whole life), seconds.");
  for (const service::RpcMetrics::Method& m : methods) {
    w->Histogram("grpc_server_handling_seconds", m.handling, labels(m));
  }
  w->Family("mapd_ingest_batches_rejected_total", "counter",
            "Batches refused inside Ingest streams (bad input, permission, shutdown), by code.");
  for (const auto& [code, n] : rpc.RejectedBatches()) {
    w->Sample("mapd_ingest_batches_rejected_total", static_cast<double>(n),
              std::string("grpc_code=\"") + service::GrpcCodeName(code) + "\"");
  }
  w->Family("mapd_submap_uploads_refused_total", "counter",
            "UploadSubmap calls that stored nothing, by code.");
  for (const auto& [code, n] : rpc.RefusedUploads()) {
    w->Sample("mapd_submap_uploads_refused_total", static_cast<double>(n),
              std::string("grpc_code=\"") + service::GrpcCodeName(code) + "\"");
  }
  w->Family("mapd_merge_duration_seconds", "histogram",
            "Time a voxel merge computed (MergeSubmaps), seconds.");
  w->Histogram("mapd_merge_duration_seconds", rpc.MergeSeconds());
  const service::RpcMetrics::Prepared prepared = rpc.PreparedSubmaps();
  w->Family("mapd_prepared_submaps", "gauge",
            "Submaps read and levelled ahead of their merges, kept (merge.prepared_submaps_mib).");
  w->Sample("mapd_prepared_submaps", static_cast<double>(prepared.count));
  w->Family("mapd_prepared_submap_bytes", "gauge", "Memory those prepared submaps hold, bytes.");
  w->Sample("mapd_prepared_submap_bytes", static_cast<double>(prepared.bytes));
}

}  // namespace

std::string MetricsText(service::Core& core) {
  const service::CoreStats s = core.Stats();
  Writer w;
  w.Family("mapd_ingest_batches_total", "counter", "Batches stored by this process.");
  w.Sample("mapd_ingest_batches_total", static_cast<double>(s.batches_stored));
  w.Family("mapd_ingest_features_total", "counter", "Raw features stored by this process.");
  w.Sample("mapd_ingest_features_total", static_cast<double>(s.features_stored));
  w.Family("mapd_ack_latency_seconds", "histogram",
           "Time from a stored batch's arrival to its (durable) acknowledgement.");
  w.Histogram("mapd_ack_latency_seconds", s.ack_latency);
  w.Family("mapd_fusion_backlog", "gauge", "Acknowledged observations not fused yet.");
  w.Sample("mapd_fusion_backlog", static_cast<double>(s.fusion_backlog));
  w.Family("mapd_fusion_share_refused_total", "counter",
           "Batches refused because their robot kept the fuser far busier than the others.");
  w.Sample("mapd_fusion_share_refused_total", static_cast<double>(s.fusion_share_refused));
  w.Family("mapd_map_version", "gauge", "Observations the published map reflects.");
  w.Sample("mapd_map_version", static_cast<double>(s.map_version));
  w.Family("mapd_fused_features", "gauge", "Published fused features (walls).");
  w.Sample("mapd_fused_features", static_cast<double>(s.fused_features));
  w.Family("mapd_retired_walls", "gauge",
           "Published walls retired because robots saw through them since they were last seen.");
  w.Sample("mapd_retired_walls", static_cast<double>(s.retired_walls));
  w.Family("mapd_fused_planes", "gauge", "Published fused non-vertical planes.");
  w.Sample("mapd_fused_planes", static_cast<double>(s.fused_planes));
  w.Family("mapd_db_size_bytes", "gauge", "Database file plus WAL.");
  w.Sample("mapd_db_size_bytes", static_cast<double>(core.store().SizeBytes()));
  w.Family("mapd_writable", "gauge", "1 while the database takes writes.");
  w.Sample("mapd_writable", s.write_failure.empty() ? 1 : 0);
  w.Family("mapd_merges", "gauge", "Merge records by state.");
  std::map<std::string, int> by_state = {
      {"proposed", 0}, {"accepted", 0}, {"rejected", 0}, {"refused", 0}};
  if (auto merges = core.store().ListMerges(); merges.ok()) {
    for (const storage::MergeRecord& r : *merges) ++by_state[storage::MergeStateName(r.state)];
  }
  for (const auto& [state, n] : by_state) w.Sample("mapd_merges", n, "state=\"" + state + "\"");
  w.Family("mapd_watchers", "gauge", "Open change feeds (WatchFeatureMap and /api/events).");
  w.Sample("mapd_watchers", static_cast<double>(core.watch_hub().watchers()));
  w.Family("mapd_uptime_seconds", "gauge", "Seconds since mapd started.");
  w.Sample("mapd_uptime_seconds", s.uptime_s);
  RpcFamilies(&w);
  w.Family("mapd_build_info", "gauge", "Always 1; the version of this mapd in its label.");
  w.Sample("mapd_build_info", 1, "version=\"" MAPD_VERSION "\"");
  if (const ProcessSample p = SampleProcess(); p.ok) {
    w.Family("process_cpu_seconds_total", "counter", "User and system CPU time, seconds.");
    w.Sample("process_cpu_seconds_total", p.cpu_s);
    w.Family("process_resident_memory_bytes", "gauge", "Resident memory size in bytes.");
    w.Sample("process_resident_memory_bytes", p.rss_bytes);
    w.Family("process_virtual_memory_bytes", "gauge", "Virtual memory size in bytes.");
    w.Sample("process_virtual_memory_bytes", p.vsize_bytes);
    w.Family("process_start_time_seconds", "gauge", "Start time since the Unix epoch, seconds.");
    w.Sample("process_start_time_seconds", p.start_time_s);
    w.Family("process_open_fds", "gauge", "Open file descriptors.");
    w.Sample("process_open_fds", p.open_fds);
    w.Family("process_max_fds", "gauge", "Maximum number of open file descriptors.");
    w.Sample("process_max_fds", p.max_fds);
  }
  return std::move(w.text());
}

}  // namespace mapd::web
