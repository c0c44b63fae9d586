// A Store on a fresh database file for each test, shared by the storage tests.
#ifndef MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_
#define MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_

#include <gtest/gtest.h>

#include <memory>
#include <utility>

#include "common/temp_dir.h"
#include "storage/store.h"

namespace mapd::storage::testing {

class StoreFixture : public ::testing::Test {
 protected:
  void SetUp() override { Reopen(); }

  // Closes the store (if open) and opens the same file again.
  void Reopen() {
    store_.reset();
    auto opened = Store::Open(dir_.File("map.db"), StoreOptions{});
    ASSERT_TRUE(opened.ok()) << opened.status().ToString();
    store_ = std::move(opened).value();
  }

  // Runs `fn` in one write transaction and commits it when fn succeeds.
  template <typename Fn>
  Status Write(Fn fn) {
    auto txn = store_->BeginWrite();
    if (!txn.ok()) return txn.status();
    Status s = fn(txn->get());
    if (!s.ok()) return s;
    return (*txn)->Commit();
  }

  mapd::testing::TempDir dir_;
  std::unique_ptr<Store> store_;
};

}  // namespace mapd::storage::testing

#endif  // MAPD_TESTS_STORAGE_SUPPORT_STORE_FIXTURE_H_
