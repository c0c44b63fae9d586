// mapd-health: asks a running mapd for grpc.health.v1.Health/Check (the
// server's overall status) and turns the answer into an exit code, for
// container HEALTHCHECKs and service monitors.
//
//   mapd-health [--server HOST:PORT] [--timeout S] [--tls-ca PEM [--tls-name NAME]]
//
// Exit codes: 0 SERVING; 1 NOT_SERVING (e.g. still replaying its fusion
// snapshot) or UNKNOWN; 2 usage error; 3 unreachable or the call failed.
// The health service answers without credentials, so the probe needs no token.
// Debian ships gRPC's health service but no client stubs for it: the call goes
// through the generic stub, with the two-byte message encoded by hand.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <future>
#include <sstream>
#include <string>
#include <vector>

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

namespace {

int Usage(const std::string& what) {
  std::fprintf(stderr,
               "mapd-health: %s\nusage: mapd-health [--server HOST:PORT] [--timeout S] "
               "[--tls-ca PEM [--tls-name NAME]]\n",
               what.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string server = "127.0.0.1:50051", ca_path, tls_name;
  double timeout_s = 5.0;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--help" || flag == "-h") return Usage("health of a running mapd"), 0;
    if (i + 1 >= argc) return Usage(flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--server") {
      server = value;
    } else if (flag == "--tls-ca") {
      ca_path = value;
    } else if (flag == "--tls-name") {
      tls_name = value;
    } else if (flag == "--timeout") {
      char* end = nullptr;
      timeout_s = std::strtod(value.c_str(), &end);
      if (*end != '\0' || !(timeout_s > 0 && timeout_s < 3600)) return Usage("--timeout wants seconds");
    } else {
      return Usage("unknown flag '" + flag + "'");
    }
  }
  std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
  grpc::ChannelArguments args;
  if (!ca_path.empty()) {
    std::ifstream in(ca_path, std::ios::binary);
    if (!in) return Usage("cannot read --tls-ca '" + ca_path + "'");
    std::ostringstream pem;
    pem << in.rdbuf();
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = pem.str();
    credentials = grpc::SslCredentials(ssl);
    // Dialling 127.0.0.1 while the certificate names the public host.
    if (!tls_name.empty()) args.SetSslTargetNameOverride(tls_name);
  } else if (!tls_name.empty()) {
    return Usage("--tls-name needs --tls-ca");
  }

  grpc::GenericStub stub(grpc::CreateCustomChannel(server, credentials, args));
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() +
                   std::chrono::milliseconds(static_cast<long>(timeout_s * 1000)));
  grpc::Slice empty(std::string{});  // HealthCheckRequest{service: ""} encodes to no bytes
  const grpc::ByteBuffer request(&empty, 1);
  grpc::ByteBuffer response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&ctx, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&done](grpc::Status s) { done.set_value(s); });
  const grpc::Status status = done.get_future().get();
  if (!status.ok()) {
    std::fprintf(stderr, "mapd-health: %s: %s (code %d)\n", server.c_str(), status.error_message().c_str(),
                 static_cast<int>(status.error_code()));
    return 3;
  }
  std::vector<grpc::Slice> slices;
  if (!response.Dump(&slices).ok()) return 3;
  std::string bytes;
  for (const grpc::Slice& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  // HealthCheckResponse{status}: field 1, varint; proto3 omits 0 (UNKNOWN).
  const int code = bytes.size() == 2 && bytes[0] == 0x08 ? bytes[1] : 0;
  const char* names[] = {"UNKNOWN", "SERVING", "NOT_SERVING"};
  std::printf("%s %s\n", server.c_str(), code >= 0 && code <= 2 ? names[code] : "UNKNOWN");
  return code == 1 ? 0 : 1;
}
