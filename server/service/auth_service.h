// The identity RPCs of mapserver.v1.MapService: CreateToken, ListTokens,
// RevokeToken (role admin), ListAudit (operator, admin), WhoAmI (anyone
// authenticated). MapServiceImpl delegates to this class. Token changes are
// audited in the transaction that makes them.
#ifndef MAPD_SERVICE_AUTH_SERVICE_H_
#define MAPD_SERVICE_AUTH_SERVICE_H_

#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/access_control.h"
#include "service/core.h"

namespace mapd::service {

class AuthService {
 public:
  AuthService(Core* core, AccessControl* access) : core_(core), access_(access) {}

  grpc::Status CreateToken(const grpc::ServerContextBase& context,
                           const mapserver::v1::CreateTokenRequest& request,
                           mapserver::v1::CreateTokenResponse* response);
  grpc::Status ListTokens(const grpc::ServerContextBase& context,
                          mapserver::v1::ListTokensResponse* response);
  grpc::Status RevokeToken(const grpc::ServerContextBase& context,
                           const mapserver::v1::RevokeTokenRequest& request,
                           mapserver::v1::RevokeTokenResponse* response);
  grpc::Status ListAudit(const grpc::ServerContextBase& context,
                         const mapserver::v1::ListAuditRequest& request,
                         mapserver::v1::ListAuditResponse* response);
  grpc::Status WhoAmI(const grpc::ServerContextBase& context,
                      mapserver::v1::WhoAmIResponse* response);

 private:
  Core* const core_;
  AccessControl* const access_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_AUTH_SERVICE_H_
