// A fixed-bucket latency histogram with lock-free recording, for the ack
// latency of ingested batches (/metrics on the web port, CoreStats).
#ifndef MAPD_SERVICE_LATENCY_HISTOGRAM_H_
#define MAPD_SERVICE_LATENCY_HISTOGRAM_H_

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

namespace mapd::service {

// What a histogram held at one moment, in Prometheus' shape: counts[i] is
// the number of samples <= bounds_s[i] (cumulative); count includes those
// above the last bound.
struct HistogramSnapshot {
  std::vector<double> bounds_s;
  std::vector<uint64_t> counts;
  uint64_t count = 0;
  double sum_s = 0;
};

class LatencyHistogram {
 public:
  // Upper bounds, seconds: group commits take ~1-50 ms on a healthy disk.
  static constexpr std::array<double, 12> kBounds = {0.001, 0.002, 0.005, 0.01, 0.025, 0.05,
                                                     0.1,   0.25,  0.5,   1.0,  2.5,   10.0};

  void Record(double seconds) {
    size_t i = 0;
    while (i < kBounds.size() && seconds > kBounds[i]) ++i;
    buckets_[i].fetch_add(1, std::memory_order_relaxed);
    sum_us_.fetch_add(static_cast<uint64_t>(seconds * 1e6), std::memory_order_relaxed);
  }

  HistogramSnapshot Snapshot() const {
    HistogramSnapshot s;
    uint64_t total = 0;
    for (size_t i = 0; i < kBounds.size(); ++i) {
      total += buckets_[i].load(std::memory_order_relaxed);
      s.bounds_s.push_back(kBounds[i]);
      s.counts.push_back(total);
    }
    s.count = total + buckets_[kBounds.size()].load(std::memory_order_relaxed);
    s.sum_s = static_cast<double>(sum_us_.load(std::memory_order_relaxed)) * 1e-6;
    return s;
  }

 private:
  std::array<std::atomic<uint64_t>, kBounds.size() + 1> buckets_{};  // the last: above all
  std::atomic<uint64_t> sum_us_{0};
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_LATENCY_HISTOGRAM_H_
