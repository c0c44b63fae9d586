// HTTP/2 rapid-reset flood (CVE-2023-44487) against a real mapd, directly or
// through HAProxy with the shipped deploy/haproxy.cfg, optionally with CPU
// hogs beside it (a busy machine): what a normal robot's acknowledgements and
// health checks cost during the flood, how much of it reached mapd (its Ingest
// calls, from /metrics) and mapd's CPU time.
//
//   rapid_reset_bench [--seconds 8] [--hogs 2] [--proxy deploy/haproxy.cfg]
//                     [--source 127.0.0.2] [--mapd PATH]
//
// Target (issue "Hardening, second round", item 6): the robot's every ack
// within 1 s under the flood with the machine busy. Not a test: run it on
// demand (docs/reliability.md, "Rapid reset").
#include <unistd.h>

#include <cstdio>
#include <string>
#include <thread>

#include "common/haproxy.h"
#include "common/latency_probes.h"
#include "common/mapd_metrics.h"
#include "common/process.h"
#include "common/rapid_reset.h"
#include "common/temp_dir.h"

namespace t = mapd::testing;

int main(int argc, char** argv) {
  double seconds = 8;
  int hogs = 0;
  std::string proxy_config, source = "127.0.0.2", mapd_binary = t::kDefaultMapdBinary;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 >= argc)
      return std::fprintf(stderr, "rapid_reset_bench: %s needs a value\n", argv[i]), 2;
    const std::string v = argv[++i];
    if (k == "--seconds")
      seconds = std::stod(v);
    else if (k == "--hogs")
      hogs = std::stoi(v);
    else if (k == "--proxy")
      proxy_config = v;
    else if (k == "--source")
      source = v;
    else if (k == "--mapd")
      mapd_binary = v;
    else
      return std::fprintf(stderr, "rapid_reset_bench: unknown flag %s\n", k.c_str()), 2;
  }
  t::TempDir dir;
  const int web_port = t::FreeLoopbackPort();
  const t::MapdProcess mapd =
      t::StartMapd(dir.File("map.db"), {"--http.port", std::to_string(web_port)}, mapd_binary);
  if (mapd.port == 0)
    return std::fprintf(stderr, "mapd did not start:\n%s\n", mapd.log().c_str()), 1;
  std::string front = mapd.address;
  t::HaproxyProcess proxy;
  if (!proxy_config.empty()) {
    proxy = t::StartHaproxy(proxy_config, mapd.address, dir.File("haproxy.log"));
    if (proxy.pid < 0)
      return std::fprintf(stderr, "haproxy did not start:\n%s\n", proxy.log().c_str()), 1;
    front = proxy.address;
  }
  const int front_port = std::atoi(front.substr(front.rfind(':') + 1).c_str());

  t::LatencyProbes probes(front);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const double calls_before = t::IngestCallsHandled(web_port), cpu_before = t::CpuSeconds(mapd.pid);
  t::RapidResetResult flood;
  {
    t::CpuHogs busy(hogs);
    t::RapidResetTarget target;
    target.port = front_port;
    target.source_host = source;
    flood = t::RunRapidReset(target, std::chrono::duration<double>(seconds));
  }
  const double cpu_flood = t::CpuSeconds(mapd.pid) - cpu_before;
  const double calls = t::IngestCallsHandled(web_port) - calls_before;
  const t::LatencyProbes::Result r = probes.Stop();
  const int proxy_exit = proxy.pid > 0 ? t::Stop(proxy.pid) : 0;
  const int mapd_exit = t::Stop(mapd.pid);

  std::printf("setup: %s, %d CPU hogs, flood from %s for %.0f s\n",
              proxy_config.empty() ? "mapd directly" : "through haproxy", hogs, source.c_str(),
              seconds);
  std::printf(
      "flood: %ld streams opened and reset in %.2f s (%.0f/s) on %ld connections (%ld closed by "
      "the peer, %ld connects refused; at most %ld streams on one); the peer reset %ld streams "
      "and sent %ld GOAWAY\n",
      flood.streams, flood.seconds, flood.streams / std::max(flood.seconds, 1e-9),
      flood.connections, flood.closed_by_peer, flood.failed_connects,
      flood.most_streams_on_one_connection, flood.resets_received, flood.goaways);
  std::printf("mapd: %.0f Ingest calls handled during the flood, %.2f CPU s\n", calls, cpu_flood);
  std::printf(
      "robot: %ld batches sent, %zu acked (%ld stored, %ld other); ack p50 %.1f ms, p99 %.1f ms, "
      "max %.1f ms\n",
      r.batches_sent, r.ack_ms.size(), r.acks_stored, r.acks_other, t::Quantile(r.ack_ms, 0.5),
      t::Quantile(r.ack_ms, 0.99), t::Quantile(r.ack_ms, 1.0));
  std::printf("health: %zu answered, %ld failed; p50 %.1f ms, p99 %.1f ms, max %.1f ms\n",
              r.health_ms.size(), r.health_failures, t::Quantile(r.health_ms, 0.5),
              t::Quantile(r.health_ms, 0.99), t::Quantile(r.health_ms, 1.0));
  std::printf("exit: mapd %d, haproxy %d\n", mapd_exit, proxy_exit);
  return 0;
}
