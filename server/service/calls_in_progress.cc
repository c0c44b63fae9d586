#include "service/calls_in_progress.h"

#include <string_view>
#include <thread>

namespace mapd::service {
namespace {

namespace gx = grpc::experimental;

// Counts itself in for as long as gRPC keeps the call (one per call).
class CallCounter : public gx::Interceptor {
 public:
  explicit CallCounter(std::atomic<int64_t>* count) : count_(count) { ++*count_; }
  ~CallCounter() override { --*count_; }
  void Intercept(gx::InterceptorBatchMethods* methods) override { methods->Proceed(); }

 private:
  std::atomic<int64_t>* const count_;
};

// Interceptors that do nothing cost gRPC nothing but a call to Proceed.
class PassThrough : public gx::Interceptor {
 public:
  void Intercept(gx::InterceptorBatchMethods* methods) override { methods->Proceed(); }
};

class CallCounterFactory : public gx::ServerInterceptorFactoryInterface {
 public:
  explicit CallCounterFactory(std::atomic<int64_t>* count) : count_(count) {}
  gx::Interceptor* CreateServerInterceptor(gx::ServerRpcInfo* info) override {
    const std::string_view method = info->method() != nullptr ? info->method() : "";
    if (method == "/grpc.health.v1.Health/Watch") return new PassThrough();
    return new CallCounter(count_);
  }

 private:
  std::atomic<int64_t>* const count_;
};

}  // namespace

std::unique_ptr<gx::ServerInterceptorFactoryInterface> CallsInProgress::InterceptorFactory() {
  return std::make_unique<CallCounterFactory>(&count_);
}

bool CallsInProgress::WaitUntilNone(std::chrono::steady_clock::time_point deadline) const {
  while (count_.load() > 0) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace mapd::service
