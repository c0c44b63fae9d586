#include "service/fusion_share.h"

#include <chrono>
#include <cstdio>

#include "service/log.h"

namespace mapd::service {
namespace {

// One log line per robot per this long at most: a refused robot retries
// many times a second.
constexpr auto kLogEvery = std::chrono::seconds(10);

}  // namespace

double FusionShare::UnmeasuredCost() const {
  double sum = 0.0;
  int measured = 0;
  for (const auto& [name, r] : robots_) {
    if (r.cost_s > 0.0) sum += r.cost_s, ++measured;
  }
  return measured > 0 ? sum / measured : kDefaultCostS;
}

Status FusionShare::Admit(const std::string& robot) {
  if (options_.after_s <= 0.0) return Status::Ok();
  std::string message;
  uint64_t refused = 0;
  {
    std::lock_guard<std::mutex> lock(mu_);
    auto self = robots_.find(robot);
    // A robot with nothing waiting keeps nobody waiting.
    if (self == robots_.end() || self->second.pending == 0) return Status::Ok();
    const double unmeasured_s = UnmeasuredCost();  // once, not per robot
    double total_s = 0.0, own_s = 0.0;
    int others = 0;
    for (const auto& [name, r] : robots_) {
      if (r.pending == 0) continue;
      const double waiting_s =
          static_cast<double>(r.pending) * (r.cost_s > 0.0 ? r.cost_s : unmeasured_s);
      total_s += waiting_s;
      if (name == robot) {
        own_s = waiting_s;
      } else {
        ++others;
      }
    }
    if (total_s < options_.after_s || others == 0) return Status::Ok();
    const double others_avg_s = (total_s - own_s) / others;
    if (own_s <= options_.factor * others_avg_s) return Status::Ok();
    Robot& r = self->second;
    refused = ++r.refused;
    ++refused_total_;
    char text[512];
    std::snprintf(text, sizeof(text),
                  "robot %s keeps the fuser busy: %llu of its observations wait for fusion "
                  "(about %.3f s of work) while the other %d robot(s) average %.3f s; once "
                  "%.3f s of fusion work waits (limits.fusion_share_after_s) a robot may keep "
                  "at most %.3g times the others' average (limits.fusion_share_factor). Nothing "
                  "was stored: resend later, or send fewer or cheaper features",
                  robot.substr(0, 64).c_str(), static_cast<unsigned long long>(r.pending), own_s,
                  others, others_avg_s, options_.after_s, options_.factor);
    message = text;
    const auto now = std::chrono::steady_clock::now();
    if (now - r.last_logged < kLogEvery) return Status::ResourceExhausted(message);
    r.last_logged = now;
  }
  Log(LogLevel::kWarn, "fusion_share_exceeded",
      {{"robot", robot.substr(0, 64)}, {"refused", std::to_string(refused)}, {"reason", message}});
  return Status::ResourceExhausted(message);
}

void FusionShare::Committed(const std::string& robot) {
  std::lock_guard<std::mutex> lock(mu_);
  ++robots_[robot].pending;
}

void FusionShare::Fused(const std::string& robot, std::optional<double> cpu_s) {
  std::lock_guard<std::mutex> lock(mu_);
  Robot& r = robots_[robot];
  if (r.pending > 0) --r.pending;
  if (!cpu_s) return;
  r.cost_s = r.cost_s > 0.0 ? (1.0 - kCostWeight) * r.cost_s + kCostWeight * *cpu_s : *cpu_s;
}

void FusionShare::Reset() {
  std::lock_guard<std::mutex> lock(mu_);
  for (auto& [name, r] : robots_) r.pending = 0;
}

std::vector<FusionShare::RobotShare> FusionShare::Shares() const {
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<RobotShare> out;
  const double unmeasured_s = UnmeasuredCost();
  for (const auto& [name, r] : robots_) {
    if (r.pending == 0 && r.refused == 0) continue;
    out.push_back({name, r.pending, r.cost_s > 0.0 ? r.cost_s : unmeasured_s, r.refused});
  }
  return out;
}

uint64_t FusionShare::refused_total() const {
  std::lock_guard<std::mutex> lock(mu_);
  return refused_total_;
}

}  // namespace mapd::service
