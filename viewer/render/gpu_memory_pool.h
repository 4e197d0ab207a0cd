// The GPU memory budget the scenes of one context share (voxview --gpu-memory): what is resident, in pieces
// that an owner can upload and evict on its own (a GpuScene's texture spans), and which to evict when room
// is needed: the least recently used that the current use does not need. Pure bookkeeping (no GL), so
// that the budget is tested by counting bytes.
//
//   const auto use = pool.begin_use();               // one frame's draw of one scene
//   pool.touch(owner, piece, use);                   // each resident piece the frame needs: not evicted now
//   if (pool.reserve(bytes, use)) { upload; pool.add(owner, piece, bytes, use); }
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "viewer/render/upload_tally.h"

namespace vxl {

class GpuMemoryPool {
 public:
  // Called to evict a piece: the owner frees it (and may not call back into the pool).
  using Evict = std::function<void(std::uint32_t piece)>;

  explicit GpuMemoryPool(std::uint64_t budget = std::numeric_limits<std::uint64_t>::max()) : budget_(budget) {}

  // An owner of pieces (a scene) and how to evict one of them; returns its id.
  std::uint32_t add_owner(Evict evict);
  // The owner is going away: its pieces are forgotten (it frees them itself).
  void remove_owner(std::uint32_t owner);

  // A new use: pieces touched or added with it are not evicted until the next one.
  std::uint64_t begin_use() { return ++use_; }
  void touch(std::uint32_t owner, std::uint32_t piece, std::uint64_t use);
  // Makes room for `bytes` more, evicting the least recently used pieces that `use` has not touched.
  // False when that cannot be done (nothing is evicted then).
  bool reserve(std::uint64_t bytes, std::uint64_t use);
  // Whether `bytes` more fit without evicting anything.
  bool fits(std::uint64_t bytes) const { return bytes <= budget_ - std::min(budget_, used_); }
  // A piece now resident (after a successful reserve of its bytes), and one freed by its owner.
  void add(std::uint32_t owner, std::uint32_t piece, std::uint64_t bytes, std::uint64_t use);
  void remove(std::uint32_t owner, std::uint32_t piece);

  std::uint64_t budget() const { return budget_; }
  std::uint64_t used() const { return used_; }
  std::uint64_t peak() const { return peak_; }            // the most ever resident
  std::uint64_t evictions() const { return evictions_; }  // pieces evicted to make room
  std::uint64_t additions() const { return additions_; }  // pieces added (uploads)
  // What the scenes sharing the pool copied to the GPU, and how fast (upload_tally.h).
  const UploadTally& uploads() const { return uploads_; }
  UploadTally& uploads() { return uploads_; }

 private:
  struct Entry {
    std::uint32_t owner, piece;
    std::uint64_t bytes, last_use;
  };
  std::uint64_t budget_;
  std::uint64_t used_ = 0, peak_ = 0, evictions_ = 0, additions_ = 0, use_ = 0;
  std::vector<Entry> entries_;  // resident pieces (a scene has tens to thousands of them)
  std::vector<Evict> owners_;   // empty function: removed
  UploadTally uploads_;
};

}  // namespace vxl
