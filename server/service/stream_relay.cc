#include "service/stream_relay.h"

#include <grpcpp/generic/generic_stub.h>

#include <mutex>

#include "service/map_router.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

constexpr char kIngestMethod[] = "/mapserver.v1.MapService/Ingest";

// What both relays share: the call to the owner, and their end. The
// caller's stream is finished with the owner's status once the owner's call
// is done; the relay is deleted once the caller's call is done too.
class RelayEnd {
 protected:
  RelayEnd(grpc::CallbackServerContext* context, std::unique_ptr<grpc::ClientContext> upstream,
           std::string owner, StreamSlot slot)
      : context_(context),
        upstream_(std::move(upstream)),
        owner_(std::move(owner)),
        slot_(std::move(slot)) {}
  virtual ~RelayEnd() = default;

  // The owner's call is done: the caller's status, with the owner's
  // redirect metadata (or, when it could not be reached, its address).
  grpc::Status Ending(const grpc::Status& status) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      upstream_done_ = true;
    }
    MapForwarder::CopyRedirect(*upstream_, *context_);
    if (status.error_code() == grpc::StatusCode::UNAVAILABLE &&
        upstream_->GetServerTrailingMetadata().count(kMapOwnerMetadata) == 0) {
      context_->AddTrailingMetadata(kMapOwnerMetadata, owner_);
    }
    return status;
  }
  // Runs `start` on the owner's call unless it is done (under the lock, so
  // that nothing is started on a call after its OnDone).
  template <typename F>
  void IfUpstreamOpen(F start) {
    std::lock_guard<std::mutex> lock(mu_);
    if (!upstream_done_) start();
  }
  // One half is done; the second deletes the relay.
  void HalfDone() {
    bool last = false;
    {
      std::lock_guard<std::mutex> lock(mu_);
      last = ++halves_done_ == 2;
    }
    if (last) delete this;
  }

  grpc::CallbackServerContext* const context_;
  const std::unique_ptr<grpc::ClientContext> upstream_;
  const std::string owner_;

 private:
  StreamSlot slot_;  // released with the relay
  std::mutex mu_;
  bool upstream_done_ = false;  // GUARDED_BY(mu_)
  int halves_done_ = 0;         // GUARDED_BY(mu_)
};

class IngestRelay final : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>,
                          public RelayEnd {
 public:
  IngestRelay(grpc::CallbackServerContext* context, std::unique_ptr<grpc::ClientContext> upstream,
              std::string owner, StreamSlot slot, grpc::GenericStub* stub)
      : RelayEnd(context, std::move(upstream), std::move(owner), std::move(slot)), to_owner_(this) {
    stub->PrepareBidiStreamingCall(upstream_.get(), kIngestMethod, grpc::StubOptions(), &to_owner_);
    to_owner_.StartRead(&from_owner_);
    to_owner_.StartCall();
    StartRead(&from_robot_);
  }

  // The robot's side.
  void OnReadDone(bool ok) override {
    IfUpstreamOpen([&] {
      if (ok) {
        to_owner_.StartWrite(&from_robot_);
      } else {
        to_owner_.StartWritesDone();  // the robot is done sending
      }
    });
  }
  void OnWriteDone(bool ok) override {  // an ack written to the robot
    if (!ok) return upstream_->TryCancel();
    IfUpstreamOpen([&] { to_owner_.StartRead(&from_owner_); });
  }
  void OnCancel() override { upstream_->TryCancel(); }
  void OnDone() override { HalfDone(); }

 private:
  class ToOwner final : public grpc::ClientBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
   public:
    explicit ToOwner(IngestRelay* relay) : relay_(relay) {}
    void OnReadDone(bool ok) override {  // an ack from the owner
      if (ok) relay_->StartWrite(&relay_->from_owner_);
    }
    void OnWriteDone(bool ok) override {  // a batch written to the owner
      if (ok) relay_->StartRead(&relay_->from_robot_);
    }
    void OnDone(const grpc::Status& status) override {
      relay_->Finish(relay_->Ending(status));
      relay_->HalfDone();
    }

   private:
    IngestRelay* const relay_;
  };

  ToOwner to_owner_;
  grpc::ByteBuffer from_robot_;  // read from the robot, then written to the owner
  grpc::ByteBuffer from_owner_;  // read from the owner, then written to the robot
};

class UploadRelay final : public grpc::ServerReadReactor<pb::UploadSubmapRequest>, public RelayEnd {
 public:
  UploadRelay(grpc::CallbackServerContext* context, std::unique_ptr<grpc::ClientContext> upstream,
              std::string owner, StreamSlot slot, pb::SubmapInfo* response,
              pb::MapService::Stub* stub)
      : RelayEnd(context, std::move(upstream), std::move(owner), std::move(slot)),
        response_(response),
        to_owner_(this) {
    stub->async()->UploadSubmap(upstream_.get(), response_, &to_owner_);
    to_owner_.StartCall();
    StartRead(&chunk_);
  }

  void OnReadDone(bool ok) override {
    IfUpstreamOpen([&] {
      if (ok) {
        to_owner_.StartWrite(&chunk_);
      } else {
        to_owner_.StartWritesDone();
      }
    });
  }
  void OnCancel() override { upstream_->TryCancel(); }
  void OnDone() override { HalfDone(); }

 private:
  class ToOwner final : public grpc::ClientWriteReactor<pb::UploadSubmapRequest> {
   public:
    explicit ToOwner(UploadRelay* relay) : relay_(relay) {}
    void OnWriteDone(bool ok) override {
      if (ok) relay_->StartRead(&relay_->chunk_);
    }
    void OnDone(const grpc::Status& status) override {
      relay_->Finish(relay_->Ending(status));  // response_ holds the owner's answer
      relay_->HalfDone();
    }

   private:
    UploadRelay* const relay_;
  };

  pb::SubmapInfo* const response_;
  ToOwner to_owner_;
  pb::UploadSubmapRequest chunk_;  // read from the caller, then written to the owner
};

}  // namespace

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* RelayIngest(
    grpc::CallbackServerContext* context, MapForwarder* forwarder, const std::string& owner,
    StreamSlot slot) {
  return new IngestRelay(context, forwarder->ContextFor(*context), owner, std::move(slot),
                         forwarder->GenericStubTo(owner));
}

grpc::ServerReadReactor<pb::UploadSubmapRequest>* RelayUpload(grpc::CallbackServerContext* context,
                                                              pb::SubmapInfo* response,
                                                              MapForwarder* forwarder,
                                                              const std::string& owner,
                                                              StreamSlot slot) {
  return new UploadRelay(context, forwarder->ContextFor(*context), owner, std::move(slot), response,
                         forwarder->StubTo(owner));
}

}  // namespace mapd::service
