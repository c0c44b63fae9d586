#include "service/auth.h"

#include <algorithm>

namespace mapd::service {
namespace {

// The role table of docs/security.md.
bool Grants(Role role, Permission p) {
  switch (p) {
    case Permission::kReadMap:
    case Permission::kReadSubmaps:
      return true;
    case Permission::kWrite:
    case Permission::kDelete:
      return role != Role::kReader;
    case Permission::kMerge:
    case Permission::kReadAudit:
      return role == Role::kOperator || role == Role::kAdmin;
    case Permission::kManageTokens:
    case Permission::kManageMaps:
      return role == Role::kAdmin;
  }
  return false;
}

bool RobotScoped(Permission p) {
  return p == Permission::kReadSubmaps || p == Permission::kWrite || p == Permission::kDelete;
}

std::string Describe(const Principal& p) {
  if (p.anonymous) return "anonymous caller (open mode)";
  std::string s = "'" + p.name + "' (role " + RoleName(p.role);
  if (p.role == Role::kRobot) s += ", robot " + p.robot_id;
  return s + ")";
}

}  // namespace

const char* RoleName(Role role) {
  switch (role) {
    case Role::kReader:
      return "reader";
    case Role::kRobot:
      return "robot";
    case Role::kOperator:
      return "operator";
    case Role::kAdmin:
      return "admin";
  }
  return "unknown";
}

bool ParseRole(const std::string& name, Role* role) {
  for (Role r : {Role::kReader, Role::kRobot, Role::kOperator, Role::kAdmin}) {
    if (name == RoleName(r)) return *role = r, true;
  }
  return false;
}

const char* PermissionName(Permission p) {
  switch (p) {
    case Permission::kReadMap:
      return "read_map";
    case Permission::kReadSubmaps:
      return "read_submaps";
    case Permission::kWrite:
      return "write";
    case Permission::kDelete:
      return "delete";
    case Permission::kMerge:
      return "merge";
    case Permission::kReadAudit:
      return "read_audit";
    case Permission::kManageTokens:
      return "manage_tokens";
    case Permission::kManageMaps:
      return "manage_maps";
  }
  return "unknown";
}

std::string RolesGranting(Permission p) {
  std::string out;
  for (Role r : {Role::kReader, Role::kRobot, Role::kOperator, Role::kAdmin}) {
    // On any robot: a robot's scoped grant does not count here.
    if (!Grants(r, p) || (r == Role::kRobot && RobotScoped(p))) continue;
    out += (out.empty() ? "" : ", ") + std::string(RoleName(r));
  }
  return out;
}

Status Authorize(const Principal& principal, Permission permission, const std::string& action,
                 const std::string& robot) {
  if (principal.anonymous) {
    if (permission != Permission::kManageTokens) return Status::Ok();
    return Status::PermissionDenied(
        action +
        ": token management needs an admin token, and the open mode has none; create the "
        "first with `mapd token create --db FILE --role admin --name NAME`");
  }
  const bool server_wide = permission == Permission::kManageTokens ||
                           permission == Permission::kManageMaps ||
                           permission == Permission::kReadAudit;
  if (server_wide && !principal.maps.empty()) {
    return Status::PermissionDenied(action + ": " + Describe(principal) +
                                    " is scoped to maps; permission " + PermissionName(permission) +
                                    " is the server's and needs a token for every map");
  }
  if (!Grants(principal.role, permission)) {
    return Status::PermissionDenied(action + ": " + Describe(principal) + " lacks permission " +
                                    PermissionName(permission) + " (granted to " +
                                    RolesGranting(permission) + ")");
  }
  if (principal.role == Role::kRobot && RobotScoped(permission) && robot != principal.robot_id) {
    return Status::PermissionDenied(
        action + ": " + Describe(principal) + " may not touch robot '" + robot +
        "': a robot token acts only for its own robot; permission " + PermissionName(permission) +
        " on any robot is granted to " + RolesGranting(permission));
  }
  return Status::Ok();
}

Status AuthorizeMap(const Principal& principal, const std::string& map, const std::string& action) {
  if (principal.maps.empty() ||
      std::binary_search(principal.maps.begin(), principal.maps.end(), map)) {
    return Status::Ok();
  }
  std::string maps;
  for (const std::string& m : principal.maps) maps += (maps.empty() ? "" : ", ") + m;
  return Status::PermissionDenied(action + ": " + Describe(principal) + " may act on maps " + maps +
                                  " only, not on map '" + map + "'");
}

}  // namespace mapd::service
