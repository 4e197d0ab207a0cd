// Sequential writes to one region of an output file that bypass the page cache (O_DIRECT) for the
// region's whole 4 KiB blocks; the partial blocks at its two ends, which it may share with its
// neighbours, go through ordinary pwrite, each with the staging it belongs to (a buffered write waits for
// the file's direct writes in flight, so the thread that appends does not make them).
//
// Why: on a virtual machine whose host takes back the guest's free memory, every page of page cache a
// large output occupies is a fresh page the host must fault in again. Buffered writes of 2 GiB ran at
// 0.46 GB/s on the 2-core build machine, direct ones at 2.9 GB/s (dd); the 9 GB .vxl of a 10M-streamline
// tractogram spent more CPU on its page cache than on its orders. Direct writes also leave the page cache
// to the source the conversion re-reads.
#pragma once

#include <cstdint>
#include <memory>
#include <span>

#include "format/base/atomic_output.h"
#include "format/base/direct_write_queue.h"

namespace vxl {

class DirectRegionWriter {
 public:
  static constexpr std::uint64_t kBlock = 4096;  // offsets, sizes and buffers of direct I/O align to it

  // Region [offset, offset + size) of `out`'s file; `direct_fd` is that file opened with O_DIRECT
  // (AtomicOutputFile::direct_descriptor), or -1 for plain pwrite. Bytes are staged
  // staging_size(size, staging_bytes) at a time, in `staging_memory` (block-aligned, that size, owned by
  // the caller) or in a buffer of the writer's own. With a `queue` (and the caller's staging memory) a
  // full staging is handed to the queue's thread and swapped for one of its spares: the region is then
  // written when the queue is finished. Writes nothing until the first append.
  DirectRegionWriter(AtomicOutputFile& out, int direct_fd, std::uint64_t offset, std::uint64_t size,
                     std::uint64_t staging_bytes, std::uint8_t* staging_memory = nullptr,
                     DirectWriteQueue* queue = nullptr);
  // The staging buffer a region of `size` bytes takes (allocated when first needed): `staging_bytes` rounded
  // up to blocks, but no more than the region can fill (the blocks it spans, with one for where it may start
  // inside a block).
  static std::uint64_t staging_size(std::uint64_t size, std::uint64_t staging_bytes);
  DirectRegionWriter(const DirectRegionWriter&) = delete;
  DirectRegionWriter& operator=(const DirectRegionWriter&) = delete;

  // Appends the region's next bytes; the last append writes out what is staged. Throws vxl::Error
  // (Output) when a write fails, std::logic_error past the region's size. Where the file system refuses
  // direct I/O (EINVAL: tmpfs, some network file systems) it falls back to pwrite for good.
  void append(std::span<const std::uint8_t> bytes);

  // Whether the whole region has been appended (and so written).
  bool complete() const { return position_ == end_; }

  // Where the next byte appended falls in its block (the file offset modulo kBlock).
  std::uint64_t block_lead() const { return position_ % kBlock; }
  // Appends the `size` bytes at block + block_lead(), as append does, but writes their whole blocks straight from
  // `block` (block-aligned, its first block_lead() bytes the writer's to overwrite with the bytes staged before
  // them) instead of copying them through the staging: for large appends from a buffer laid out so. Not with a
  // queue (std::logic_error).
  void append_from_block(std::uint8_t* block, std::uint64_t size);

  // Writes `size` bytes from `data` at file offset `offset` (block-aligned, as `data` is) but the first `skip`
  // (less than a block): whole blocks through `direct_fd` (set to -1 where the file system refuses direct I/O:
  // then plain pwrite), a first block with bytes skipped and a last partial block through the page cache.
  // Throws vxl::Error (Output).
  static void write_blocks(AtomicOutputFile& out, int& direct_fd, const std::uint8_t* data, std::uint64_t size,
                           std::uint64_t offset, std::uint64_t skip = 0);

 private:
  void ensure_staging();  // the writer's own staging, at first need (unless the caller gave one)
  void start_staging();
  void write_staged();

  AtomicOutputFile& out_;
  int direct_fd_;
  std::uint64_t end_, position_;  // file offsets: the region's end, the next byte appended
  std::uint64_t staging_bytes_;
  std::unique_ptr<std::uint8_t, void (*)(void*)> staging_{nullptr, nullptr};
  std::uint64_t staged_ = 0;         // bytes in staging_
  std::uint64_t staging_start_ = 0;  // the file offset of staging_[0] (block-aligned)
  std::uint64_t skip_ = 0;           // staging_'s first bytes that are the neighbour's (the region's first block)
  bool staging_is_spare_ = false;    // staging_ came from the queue (a region may fill more stagings than its own)
  DirectWriteQueue* queue_;
};

}  // namespace vxl
