#include "service/token.h"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/rand.h>

#include <algorithm>

#include "service/map_id.h"

namespace mapd::service {
namespace {

constexpr char kPrefix[] = "mapd_";
constexpr size_t kSecretBytes = 32;

std::string Base64Url(const unsigned char* data, size_t n) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_";
  std::string out;
  uint32_t acc = 0;
  int bits = 0;
  for (size_t i = 0; i < n; ++i) {
    acc = (acc << 8) | data[i];
    bits += 8;
    while (bits >= 6) {
      bits -= 6;
      out += kAlphabet[(acc >> bits) & 0x3f];
    }
  }
  if (bits > 0) out += kAlphabet[(acc << (6 - bits)) & 0x3f];
  return out;
}

}  // namespace

std::string Sha256(std::string_view data) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  EVP_Digest(data.data(), data.size(), digest, &n, EVP_sha256(), nullptr);
  return std::string(reinterpret_cast<const char*>(digest), n);
}

bool ConstantTimeEqual(std::string_view a, std::string_view b) {
  return a.size() == b.size() && CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

bool ValidTokenName(const std::string& name) {
  if (name.empty() || name.size() > 128) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
  });
}

Status ParseToken(std::string_view token, int64_t* id, std::string* secret) {
  const Status bad = Status::InvalidArgument("a mapd token looks like mapd_<id>_<secret>");
  if (token.substr(0, sizeof(kPrefix) - 1) != kPrefix) return bad;
  token.remove_prefix(sizeof(kPrefix) - 1);
  const size_t sep = token.find('_');
  if (sep == 0 || sep == std::string_view::npos || sep > 18) return bad;
  int64_t v = 0;
  for (char c : token.substr(0, sep)) {
    if (c < '0' || c > '9') return bad;
    v = v * 10 + (c - '0');
  }
  *id = v;
  *secret = std::string(token.substr(sep + 1));
  return secret->empty() ? bad : Status::Ok();
}

StatusOr<IssuedToken> IssueToken(const NewToken& t, int64_t now_ns,
                                 storage::WriteTransaction* txn) {
  if (!ValidTokenName(t.name))
    return Status::InvalidArgument("name must be 1-128 characters of [A-Za-z0-9_.-]");
  if (t.role == Role::kRobot && !ValidTokenName(t.robot_id)) {
    return Status::InvalidArgument(
        "a robot token needs robot_id (1-128 characters of [A-Za-z0-9_.-])");
  }
  if (t.role != Role::kRobot && !t.robot_id.empty()) {
    return Status::InvalidArgument(std::string("robot_id is only for role robot, not ") +
                                   RoleName(t.role));
  }
  for (const std::string& map : t.maps) MAPD_RETURN_IF_ERROR(CheckMapId(map, "maps entry"));
  unsigned char raw[kSecretBytes];
  if (RAND_bytes(raw, sizeof(raw)) != 1)
    return Status::Internal("the CSPRNG (OpenSSL RAND_bytes) failed");
  const std::string secret = Base64Url(raw, sizeof(raw));
  OPENSSL_cleanse(raw, sizeof(raw));
  IssuedToken out;
  storage::TokenRecord& r = out.record;
  r.name = t.name;
  r.role = RoleName(t.role);
  r.robot_id = t.robot_id;
  r.secret_sha256 = Sha256(secret);
  r.created_ns = now_ns;
  r.created_by = t.created_by;
  std::vector<std::string> maps = t.maps;  // sorted, once each
  std::sort(maps.begin(), maps.end());
  maps.erase(std::unique(maps.begin(), maps.end()), maps.end());
  r.maps = JoinMapIds(maps);
  StatusOr<int64_t> id = txn->InsertToken(r);
  if (!id.ok()) return id.status();
  r.id = *id;
  out.token = kPrefix + std::to_string(*id) + "_" + secret;
  return out;
}

}  // namespace mapd::service
