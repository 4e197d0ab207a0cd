#include "viewer/render/gpu_memory_pool.h"

#include <algorithm>
#include <stdexcept>

namespace vxl {

std::uint32_t GpuMemoryPool::add_owner(Evict evict) {
  owners_.push_back(std::move(evict));
  return static_cast<std::uint32_t>(owners_.size() - 1);
}

void GpuMemoryPool::remove_owner(std::uint32_t owner) {
  for (const Entry& e : entries_)
    if (e.owner == owner) used_ -= e.bytes;
  std::erase_if(entries_, [&](const Entry& e) { return e.owner == owner; });
  owners_.at(owner) = nullptr;
}

void GpuMemoryPool::touch(std::uint32_t owner, std::uint32_t piece, std::uint64_t use) {
  for (Entry& e : entries_)
    if (e.owner == owner && e.piece == piece) e.last_use = use;
}

bool GpuMemoryPool::reserve(std::uint64_t bytes, std::uint64_t use) {
  if (bytes > budget_) return false;
  // What eviction can free: everything the current use has not touched.
  std::uint64_t evictable = 0;
  for (const Entry& e : entries_)
    if (e.last_use != use) evictable += e.bytes;
  if (used_ - evictable + bytes > budget_) return false;
  while (used_ + bytes > budget_) {
    const auto lru = std::min_element(entries_.begin(), entries_.end(), [&](const Entry& a, const Entry& b) {
      return (a.last_use == use ? 1 : 0) < (b.last_use == use ? 1 : 0) ||
             ((a.last_use == use) == (b.last_use == use) && a.last_use < b.last_use);
    });
    const Entry victim = *lru;
    entries_.erase(lru);
    used_ -= victim.bytes;
    ++evictions_;
    owners_.at(victim.owner)(victim.piece);
  }
  return true;
}

void GpuMemoryPool::add(std::uint32_t owner, std::uint32_t piece, std::uint64_t bytes, std::uint64_t use) {
  if (!owners_.at(owner)) throw std::logic_error("GpuMemoryPool::add for a removed owner");
  entries_.push_back({owner, piece, bytes, use});
  used_ += bytes;
  ++additions_;
  peak_ = std::max(peak_, used_);
}

void GpuMemoryPool::remove(std::uint32_t owner, std::uint32_t piece) {
  const auto it = std::find_if(entries_.begin(), entries_.end(),
                               [&](const Entry& e) { return e.owner == owner && e.piece == piece; });
  if (it == entries_.end()) return;
  used_ -= it->bytes;
  entries_.erase(it);
}

}  // namespace vxl
