// The UploadSubmap RPC on gRPC's callback API: no thread is held while a
// client sends (or idles), unlike the synchronous API, where 3,000 idle
// uploads held 3,000 server threads. SubmapService admits at most
// limits.max_concurrent_uploads of them (the rest get RESOURCE_EXHAUSTED at
// once) and ends those idle for limits.upload_idle_timeout_s. Once the client
// half-closes, the bytes are validated and stored on a thread of their own
// (SubmapService::StoreUpload: no tree is built, the writer commits), never on
// a gRPC thread.
//
// Who: the caller was authenticated, and its role checked, when the stream
// was opened (MapServiceImpl::UploadSubmap). Once the header arrives, its
// robot id is checked against the caller (a robot uploads, and squats names,
// only for itself) before any chunk is accepted: a refusal is audited and
// ends the call with PERMISSION_DENIED once the audit row is committed
// (AccessControl::CheckAsync; no gRPC thread waits for that commit).
#ifndef MAPD_SERVICE_UPLOAD_REACTOR_H_
#define MAPD_SERVICE_UPLOAD_REACTOR_H_

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <mutex>
#include <string>

#include "mapserver/v1/map_service.pb.h"
#include "service/access_control.h"
#include "service/stream_limiter.h"

namespace mapd::service {

class SubmapService;

// Owned by gRPC; deletes itself in OnDone().
class UploadReactor : public grpc::ServerReadReactor<mapserver::v1::UploadSubmapRequest> {
 public:
  // Starts reading. `service` outlives every reactor (it waits for them).
  UploadReactor(SubmapService* service, grpc::CallbackServerContext* context,
                mapserver::v1::SubmapInfo* response, StreamSlot slot, Principal caller,
                CallHold hold = nullptr);

  void OnReadDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

  // Ends the upload with DEADLINE_EXCEEDED if nothing arrived for `idle_s`
  // (called by the service's housekeeping, under its registry lock).
  void ExpireIfIdle(std::chrono::steady_clock::time_point now, double idle_s);

 private:
  void FinishOnce(const grpc::Status& status);
  // After the header: true when the caller may upload for its robot id;
  // otherwise the refusal finishes the call (asynchronously, once audited).
  bool CallerMayUpload();

  const CallHold hold_;  // first: released last, after every member that uses the map
  SubmapService* const service_;
  grpc::CallbackServerContext* const context_;
  mapserver::v1::SubmapInfo* const response_;
  StreamSlot slot_;
  const Principal caller_;

  std::mutex mu_;
  mapserver::v1::UploadSubmapRequest message_;  // the buffer of the outstanding read
  bool finished_ = false;                       // GUARDED_BY(mu_)
  // GUARDED_BY(mu_): every byte is in (validating and storing), or a refusal
  // is being audited; either way that work finishes the call, not a cancel.
  bool storing_ = false;
  std::chrono::steady_clock::time_point last_activity_;  // GUARDED_BY(mu_)
  size_t messages_ = 0;                                  // read so far
  mapserver::v1::SubmapHeader header_;
  std::string bytes_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_UPLOAD_REACTOR_H_
