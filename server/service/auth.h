// Who may do what (docs/security.md). Pure policy: no gRPC, no SQL.
//
// A caller is a Principal: a token's holder or a client certificate's CN
// (server/service/access_control.h finds out which). Each RPC needs one
// Permission; a role grants a set of them. Robot-scoped permissions (write,
// delete, read_submaps for a robot) are limited to the principal's own robot
// id when the role is `robot`.
#ifndef MAPD_SERVICE_AUTH_H_
#define MAPD_SERVICE_AUTH_H_

#include <string>
#include <vector>

#include "common/status.h"

namespace mapd::service {

enum class Role { kReader, kRobot, kOperator, kAdmin };

enum class Permission {
  kReadMap,       // GetFeatureMap, WatchFeatureMap, GetGlobalMap, ListRobots, GetStats, ListMerges,
                  // GetMerge, GetTrails
  kReadSubmaps,   // ListSubmaps, GetSubmap (a robot: its own submaps only)
  kWrite,         // Ingest, UploadSubmap (a robot: its own robot id only)
  kDelete,        // DeleteSubmap (a robot: its own submaps only)
  kMerge,         // MergeSubmaps, ApproveMerge, RejectMerge
  kReadAudit,     // ListAudit
  kManageTokens,  // CreateToken, ListTokens, RevokeToken
  kManageMaps,    // CreateMap, DeleteMap, RestoreMap
};

struct Principal {
  std::string name;  // token name, certificate CN, or "anonymous"
  Role role = Role::kReader;
  std::string robot_id;  // role kRobot: the robot it acts for
  // No credential, auth not required (loopback, no tokens ever made): the
  // open mode. Acts as an operator, but never manages tokens.
  bool anonymous = false;
  // For the audit log: how the caller proved who it is ("token",
  // "certificate", "none") and its address (gRPC's peer, "ipv4:1.2.3.4:5").
  std::string credential;
  std::string peer;
  // A token's scope: the maps it may act on (sorted); empty = every map.
  std::vector<std::string> maps;
};

const char* RoleName(Role role);  // "reader", "robot", "operator", "admin"
bool ParseRole(const std::string& name, Role* role);
const char* PermissionName(Permission p);  // "read_map", "write", ...
// The roles granting `p` (on any robot), e.g. "operator, admin".
std::string RolesGranting(Permission p);

// OK, or PermissionDenied naming the principal, its role, the action and the
// permission needed. `robot` is the robot whose data is touched (empty: none
// in particular); it matters only for robot-scoped permissions.
// A token scoped to maps is refused what is the server's, not a map's
// (managing tokens and maps, reading the audit log).
Status Authorize(const Principal& principal, Permission permission, const std::string& action,
                 const std::string& robot = "");

// OK when the principal may act on `map` (its token is not scoped, or
// scoped to it), else PermissionDenied naming its maps.
Status AuthorizeMap(const Principal& principal, const std::string& map, const std::string& action);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_AUTH_H_
