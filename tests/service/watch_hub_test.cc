// WatchHub alone: the history a resume is served from, the bounded queues,
// the watcher limit, Close.
#include "service/watch_hub.h"

#include <gtest/gtest.h>

#include <memory>

namespace mapd::service {
namespace {

ChangePtr Change(uint64_t from, uint64_t to, bool empty = false) {
  auto c = std::make_shared<MapChange>();
  c->from_version = from;
  c->to_version = to;
  if (!empty) c->lines_gone.push_back(to);
  return c;
}

WatchOptions Options(size_t history, size_t queue, size_t max_watchers = 4) {
  WatchOptions o;
  o.history = history;
  o.queue = queue;
  o.max_watchers = max_watchers;
  return o;
}

TEST(WatchHubTest, AResumeInsideTheHistoryGetsTheChangesAfterIt) {
  WatchHub hub(Options(3, 8));
  hub.Start(10);
  for (uint64_t v = 10; v < 15; ++v) hub.Publish(Change(v, v + 1));  // keeps 13..15
  auto old = hub.Subscribe(11, nullptr);
  ASSERT_TRUE(old.ok());
  EXPECT_TRUE(old->resync) << "11 -> 12 is no longer held";
  auto inside = hub.Subscribe(12, nullptr);
  ASSERT_TRUE(inside.ok());
  EXPECT_FALSE(inside->resync);
  ASSERT_EQ(inside->replay.size(), 3u);
  EXPECT_EQ(inside->replay.front()->to_version, 13u);
  auto fresh = hub.Subscribe(0, nullptr);
  ASSERT_TRUE(fresh.ok());
  EXPECT_TRUE(fresh->resync);
  // Rounds that changed nothing published move the version, not the floor.
  hub.Publish(Change(15, 20, /*empty=*/true));
  EXPECT_EQ(hub.version(), 20u);
  auto at_end = hub.Subscribe(20, nullptr);
  ASSERT_TRUE(at_end.ok());
  EXPECT_FALSE(at_end->resync);
  EXPECT_TRUE(at_end->replay.empty());
}

TEST(WatchHubTest, AFullQueueMarksTheWatcherBehindInsteadOfGrowing) {
  WatchHub hub(Options(0, 2));
  hub.Start(0);
  auto sub = hub.Subscribe(0, nullptr);
  ASSERT_TRUE(sub.ok());
  for (uint64_t v = 0; v < 100; ++v) hub.Publish(Change(v, v + 1));
  ChangePtr c;
  EXPECT_EQ(sub->watcher->Take(std::chrono::seconds(0), &c), Watcher::Next::kBehind);
  EXPECT_EQ(sub->watcher->Take(std::chrono::seconds(0), &c), Watcher::Next::kTimeout);
  hub.Publish(Change(100, 101));
  ASSERT_EQ(sub->watcher->Take(std::chrono::seconds(0), &c), Watcher::Next::kChange);
  EXPECT_EQ(c->to_version, 101u);
}

TEST(WatchHubTest, WatchersAreBoundedAndCloseEndsThem) {
  WatchHub hub(Options(4, 4, 1));
  EXPECT_EQ(hub.Subscribe(0, nullptr).status().code(), StatusCode::kUnavailable) << "not started";
  hub.Start(0);
  auto one = hub.Subscribe(0, nullptr);
  ASSERT_TRUE(one.ok());
  auto two = hub.Subscribe(0, nullptr);
  EXPECT_EQ(two.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(two.status().message().find("limits.max_watchers"), std::string::npos);
  int cancelled = 0;
  hub.Unsubscribe(one->watcher);
  auto three = hub.Subscribe(0, [&] { ++cancelled; });
  ASSERT_TRUE(three.ok());
  three->watcher->SetWriting(true);  // a write in progress is cancelled
  hub.Close();
  EXPECT_EQ(cancelled, 1);
  ChangePtr c;
  EXPECT_EQ(three->watcher->Take(std::chrono::seconds(0), &c), Watcher::Next::kClosed);
  EXPECT_EQ(hub.Subscribe(0, nullptr).status().code(), StatusCode::kUnavailable);
}

}  // namespace
}  // namespace mapd::service
