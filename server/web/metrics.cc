#include "web/metrics.h"

#include <cstdio>
#include <map>

#include "service/watch_hub.h"

namespace mapd::web {
namespace {

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
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
  std::string& text() { return out_; }

 private:
  std::string out_;
};

}  // namespace

std::string MetricsText(service::Core& core) {
  const service::CoreStats s = core.Stats();
  Writer w;
  w.Family("mapd_ingest_batches_total", "counter", "Batches stored by this process.");
  w.Sample("mapd_ingest_batches_total", static_cast<double>(s.batches_stored));
  w.Family("mapd_ingest_features_total", "counter", "Raw features stored by this process.");
  w.Sample("mapd_ingest_features_total", static_cast<double>(s.features_stored));
  w.Family("mapd_ingest_batches_per_second", "gauge", "Batches stored per second, last 10 s.");
  w.Sample("mapd_ingest_batches_per_second", s.batches_per_s);
  w.Family("mapd_ack_latency_seconds", "histogram",
           "Time from a stored batch's arrival to its (durable) acknowledgement.");
  const service::HistogramSnapshot& h = s.ack_latency;
  for (size_t i = 0; i < h.bounds_s.size(); ++i)
    w.Sample("mapd_ack_latency_seconds_bucket", static_cast<double>(h.counts[i]),
             "le=\"" + Num(h.bounds_s[i]) + "\"");
  w.Sample("mapd_ack_latency_seconds_bucket", static_cast<double>(h.count), "le=\"+Inf\"");
  w.Sample("mapd_ack_latency_seconds_sum", h.sum_s);
  w.Sample("mapd_ack_latency_seconds_count", static_cast<double>(h.count));
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
  return std::move(w.text());
}

}  // namespace mapd::web
