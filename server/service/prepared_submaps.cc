#include "service/prepared_submaps.h"

#include <vector>

#include "service/voxel_merge.h"

namespace mapd::service {

void PreparedSubmaps::EraseLocked(std::map<PreparedKey, Entry>::iterator it,
                                  std::vector<View>* freed) {
  bytes_ -= it->second.bytes;
  lru_.erase(it->second.lru);
  freed->push_back(std::move(it->second.view));
  entries_.erase(it);
}

PreparedSubmaps::View PreparedSubmaps::Take(const PreparedKey& key) {
  std::lock_guard<std::mutex> lock(mu_);
  const auto it = entries_.find(key);
  if (it == entries_.end()) return nullptr;
  View view = std::move(it->second.view);
  bytes_ -= it->second.bytes;
  lru_.erase(it->second.lru);
  entries_.erase(it);
  taken_.insert(key);
  return view;
}

void PreparedSubmaps::Put(const PreparedKey& key, View view) {
  // Measured outside the lock: it walks the octree (milliseconds).
  const std::size_t bytes = view == nullptr ? 0 : PreparedVoxelSubmapBytes(*view);
  std::vector<View> freed;  // freed after the lock is released
  std::lock_guard<std::mutex> lock(mu_);
  taken_.erase(key);
  const bool forgotten = forgotten_.erase(key) > 0;
  if (view == nullptr || forgotten || closed_owners_.count(key.owner) > 0 ||
      bytes > budget_bytes_) {
    freed.push_back(std::move(view));
    return;
  }
  if (auto it = entries_.find(key); it != entries_.end())
    EraseLocked(it, &freed);  // prepared twice
  lru_.push_front(key);
  entries_.emplace(key, Entry{std::move(view), bytes, lru_.begin()});
  bytes_ += bytes;
  while (bytes_ > budget_bytes_) EraseLocked(entries_.find(lru_.back()), &freed);
}

bool PreparedSubmaps::Has(const PreparedKey& key) const {
  std::lock_guard<std::mutex> lock(mu_);
  return entries_.count(key) > 0 || taken_.count(key) > 0;
}

void PreparedSubmaps::Forget(const PreparedKey& key) {
  std::vector<View> freed;
  std::lock_guard<std::mutex> lock(mu_);
  if (taken_.count(key) > 0) forgotten_.insert(key);
  if (auto it = entries_.find(key); it != entries_.end()) EraseLocked(it, &freed);
}

void PreparedSubmaps::ForgetOwner(uint64_t owner) {
  std::vector<View> freed;
  std::lock_guard<std::mutex> lock(mu_);
  closed_owners_.insert(owner);
  for (auto it = entries_.lower_bound({owner, 0});
       it != entries_.end() && it->first.owner == owner;) {
    EraseLocked(it++, &freed);
  }
}

std::size_t PreparedSubmaps::bytes() const {
  std::lock_guard<std::mutex> lock(mu_);
  return bytes_;
}

std::size_t PreparedSubmaps::size() const {
  std::lock_guard<std::mutex> lock(mu_);
  return entries_.size();
}

}  // namespace mapd::service
