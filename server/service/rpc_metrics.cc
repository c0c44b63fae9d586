#include "service/rpc_metrics.h"

#include <chrono>

namespace mapd::service {
namespace {

namespace gx = grpc::experimental;

constexpr std::string_view kUploadSubmap = "/mapserver.v1.MapService/UploadSubmap";

// Times one call from its metadata to the status it sends. A call that ends
// without sending one (the client went away first) counts as CANCELLED.
class CallTimer : public gx::Interceptor {
 public:
  explicit CallTimer(gx::ServerRpcInfo* info)
      : method_(info->method() != nullptr ? info->method() : ""),
        start_(std::chrono::steady_clock::now()) {}
  ~CallTimer() override {
    if (!recorded_) Record(grpc::StatusCode::CANCELLED);
  }

  void Intercept(gx::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(gx::InterceptionHookPoints::PRE_SEND_STATUS)) {
      Record(methods->GetSendStatus().error_code());
    }
    methods->Proceed();
  }

 private:
  void Record(grpc::StatusCode code) {
    recorded_ = true;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    RpcMetrics::Default().RecordCall(method_, code, seconds);
  }

  const std::string method_;
  const std::chrono::steady_clock::time_point start_;
  bool recorded_ = false;
};

class CallTimerFactory : public gx::ServerInterceptorFactoryInterface {
 public:
  gx::Interceptor* CreateServerInterceptor(gx::ServerRpcInfo* info) override {
    return new CallTimer(info);
  }
};

}  // namespace

RpcMetrics& RpcMetrics::Default() {
  static RpcMetrics* metrics = new RpcMetrics();  // never destroyed: threads may record late
  return *metrics;
}

void RpcMetrics::RecordCall(std::string_view full_method, grpc::StatusCode code, double seconds) {
  Entry* entry = nullptr;
  {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = methods_.find(full_method);
    if (it == methods_.end()) {
      it = methods_.emplace(std::string(full_method), std::make_unique<Entry>()).first;
    }
    entry = it->second.get();
    ++entry->handled[code];
  }
  entry->handling.Record(seconds);  // lock-free; entries are never removed
}

void RpcMetrics::RecordRejectedBatch(grpc::StatusCode code) {
  std::lock_guard<std::mutex> lock(mu_);
  ++rejected_batches_[code];
}

void RpcMetrics::SetPreparedSubmaps(uint64_t count, uint64_t bytes) {
  std::lock_guard<std::mutex> lock(mu_);
  prepared_ = {count, bytes};
}

RpcMetrics::Prepared RpcMetrics::PreparedSubmaps() const {
  std::lock_guard<std::mutex> lock(mu_);
  return prepared_;
}

void RpcMetrics::RecordMerge(double seconds) { merges_.Record(seconds); }

std::vector<RpcMetrics::Method> RpcMetrics::Methods() const {
  std::vector<Method> out;
  std::lock_guard<std::mutex> lock(mu_);
  for (const auto& [name, entry] : methods_) {
    Method m;
    // "/package.Service/Method"
    const size_t slash = name.rfind('/');
    m.service = slash == std::string::npos || slash == 0 ? "" : name.substr(1, slash - 1);
    m.method = slash == std::string::npos ? name : name.substr(slash + 1);
    m.handled = entry->handled;
    m.handling = entry->handling.Snapshot();
    out.push_back(std::move(m));
  }
  return out;
}

std::map<grpc::StatusCode, uint64_t> RpcMetrics::RejectedBatches() const {
  std::lock_guard<std::mutex> lock(mu_);
  return rejected_batches_;
}

std::map<grpc::StatusCode, uint64_t> RpcMetrics::RefusedUploads() const {
  std::map<grpc::StatusCode, uint64_t> out;
  std::lock_guard<std::mutex> lock(mu_);
  if (auto it = methods_.find(kUploadSubmap); it != methods_.end()) {
    for (const auto& [code, n] : it->second->handled) {
      if (code != grpc::StatusCode::OK) out[code] = n;
    }
  }
  return out;
}

std::unique_ptr<gx::ServerInterceptorFactoryInterface> RpcMetrics::InterceptorFactory() {
  return std::make_unique<CallTimerFactory>();
}

const char* GrpcCodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::UNKNOWN:
      return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS:
      return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED:
      return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED:
      return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE:
      return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED:
      return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS:
      return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    default:
      return "UNKNOWN";
  }
}

}  // namespace mapd::service
