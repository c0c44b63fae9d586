// A throw-away PostgreSQL cluster for tests, started by the test itself:
// initdb in a temporary directory, a server listening on a Unix socket in
// that directory only (no TCP port to collide with), removed at the end.
// Debian's postgresql-15 provides the binaries (deploy/install-deps.sh).
//
// initdb refuses to run as root, so as root the cluster is made and run as
// the `postgres` user (runuser), in a directory handed to it.
//
//   static PostgresCluster* cluster = PostgresCluster::Shared();
//   if (cluster == nullptr) GTEST_SKIP() << "no PostgreSQL";
//   std::string conninfo = cluster->NewDatabase();  // a fresh, empty database
//
// Policy: without the binaries a test SKIPS, so a developer without
// PostgreSQL can still run the rest; CI installs them and fails on any skip
// not in tests/skips-allowed.txt, so there the PostgreSQL tests always run.
#ifndef MAPD_TESTS_COMMON_POSTGRES_H_
#define MAPD_TESTS_COMMON_POSTGRES_H_

#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "common/process.h"
#include "common/temp_dir.h"

namespace mapd::testing {

class PostgresCluster {
 public:
  // Starts a cluster, or returns null with *why set (binaries missing,
  // initdb or pg_ctl failed, with their output). `fsync` false speeds up
  // tests that never crash the machine; tests that kill PostgreSQL need it on.
  static std::unique_ptr<PostgresCluster> Start(bool fsync, std::string* why) {
    std::unique_ptr<PostgresCluster> c(new PostgresCluster());
    c->bindir_ = FindBinDir();
    if (c->bindir_.empty()) {
      *why = "PostgreSQL server binaries not found (install postgresql-15)";
      return nullptr;
    }
    c->data_ = c->dir_.File("data");
    if (getuid() == 0) {
      const passwd* pw = getpwnam("postgres");
      if (pw == nullptr) {
        *why = "running as root and there is no 'postgres' user to run initdb as";
        return nullptr;
      }
      c->run_as_ = {"/usr/sbin/runuser", "-u", "postgres", "--"};
      if (chown(c->dir_.path().c_str(), pw->pw_uid, pw->pw_gid) != 0) {
        *why = "cannot hand " + c->dir_.path() + " to the postgres user";
        return nullptr;
      }
    }
    CommandResult init = c->Run({c->bindir_ + "/initdb", "-D", c->data_, "-U", "mapd", "-A",
                                 "trust", "-E", "UTF8", "--no-sync", "--locale=C"});
    if (init.exit_code != 0) {
      *why = "initdb failed: " + init.out + init.err;
      return nullptr;
    }
    c->fsync_ = fsync;
    if (!c->StartServer(why)) return nullptr;
    return c;
  }

  // One cluster per test binary, started on first use (about 2 s); null if
  // none can be started (the reason goes to stderr once).
  static PostgresCluster* Shared() {
    static std::unique_ptr<PostgresCluster> shared = [] {
      std::string why;
      std::unique_ptr<PostgresCluster> c = Start(/*fsync=*/false, &why);
      if (c == nullptr) fprintf(stderr, "no PostgreSQL for the tests: %s\n", why.c_str());
      return c;
    }();
    return shared.get();
  }

  ~PostgresCluster() {
    if (!data_.empty()) Run({bindir_ + "/pg_ctl", "-D", data_, "-m", "immediate", "-w", "stop"});
  }
  PostgresCluster(const PostgresCluster&) = delete;
  PostgresCluster& operator=(const PostgresCluster&) = delete;

  // A libpq connection string for database `dbname` as the superuser "mapd".
  std::string Conninfo(const std::string& dbname) const {
    return "host=" + dir_.path() + " port=" + std::to_string(kPort) + " user=mapd dbname=" + dbname;
  }

  // Creates a new, empty database and returns its connection string.
  std::string NewDatabase() {
    static std::atomic<int> next{0};
    const std::string name = "t" + std::to_string(getpid()) + "_" + std::to_string(next++);
    PGconn* conn = PQconnectdb(Conninfo("postgres").c_str());
    std::string error;
    if (PQstatus(conn) != CONNECTION_OK) {
      error = PQerrorMessage(conn);
    } else {
      PGresult* r = PQexec(conn, ("CREATE DATABASE " + name).c_str());
      if (PQresultStatus(r) != PGRES_COMMAND_OK) error = PQresultErrorMessage(r);
      PQclear(r);
    }
    PQfinish(conn);
    EXPECT_EQ(error, "") << "CREATE DATABASE " << name;
    return Conninfo(name);
  }

  // Stops the server: "immediate" is a crash (no checkpoint), "fast" a clean stop.
  bool Stop(const std::string& mode) {
    return Run({bindir_ + "/pg_ctl", "-D", data_, "-m", mode, "-w", "stop"}).exit_code == 0;
  }
  bool Restart(std::string* why) { return StartServer(why); }
  std::string socket_dir() const { return dir_.path(); }

 private:
  static constexpr int kPort = 5432;  // names the socket file in our own directory only

  PostgresCluster() = default;

  static std::string FindBinDir() {
    std::vector<std::string> candidates;
    for (int v : {17, 16, 15})
      candidates.push_back("/usr/lib/postgresql/" + std::to_string(v) + "/bin");
    for (const std::string& d : candidates) {
      if (access((d + "/initdb").c_str(), X_OK) == 0 && access((d + "/pg_ctl").c_str(), X_OK) == 0)
        return d;
    }
    return "";
  }

  bool StartServer(std::string* why) {
    const std::string options = "-c listen_addresses='' -k " + dir_.path() + " -p " +
                                std::to_string(kPort) + " -c fsync=" + (fsync_ ? "on" : "off") +
                                " -c max_connections=200";
    CommandResult start = Run({bindir_ + "/pg_ctl", "-D", data_, "-l", dir_.File("server.log"),
                               "-o", options, "-w", "-t", "60", "start"});
    if (start.exit_code != 0) {
      *why =
          "pg_ctl start failed: " + start.out + start.err + ReadFileBytes(dir_.File("server.log"));
      return false;
    }
    return true;
  }

  CommandResult Run(std::vector<std::string> argv) const {
    std::vector<std::string> full = run_as_;
    full.insert(full.end(), argv.begin(), argv.end());
    return RunCommand(full, "", std::chrono::seconds(90));
  }

  TempDir dir_;
  std::string bindir_, data_;
  std::vector<std::string> run_as_;
  bool fsync_ = false;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_POSTGRES_H_
