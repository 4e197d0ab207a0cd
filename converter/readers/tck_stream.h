// A TCK file read in bounded memory, a batch of whole streamlines at a time, in as many passes as the
// caller needs (voxlines convert --memory-limit). It yields exactly what read_tck reads — the same
// points, streamlines, provenance and warnings (tck_format.h holds the shared pieces) — but one part of
// the file at a time, read into a buffer of that size, so the file adds at most one part to this
// process's resident memory.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "converter/readers/tck_format.h"
#include "converter/tractogram.h"

namespace vxl {

class Xxh3_128Stream;

class TckStream {
 public:
  // Opens `path` and parses its header, reading at most `max_header_bytes` for it (a longer header is an
  // Unsupported error that says so). `read_buffer_bytes` is the size of the read buffer. Throws vxl::Error
  // like read_tck.
  TckStream(const std::string& path, std::uint64_t max_header_bytes, std::uint64_t read_buffer_bytes = 4u << 20);
  ~TckStream();
  TckStream(const TckStream&) = delete;
  TckStream& operator=(const TckStream&) = delete;

  // What read_tck puts in Tractogram::source. xxh3_128 and the warnings about the data are filled in
  // when the first pass reaches the end (complete()).
  const SourceInfo& source() const { return source_; }
  bool complete() const { return complete_; }
  std::uint64_t file_size() const { return source_.bytes; }
  // Bytes of the file read so far in this pass (for progress).
  std::uint64_t position() const { return read_end_; }

  // Starts a pass at the first streamline. Throws vxl::Error (Input) when the file has changed size or
  // modification time since it was opened: passes must all see the same data.
  void rewind();

  // Replaces batch.positions and batch.offsets with the next whole streamlines: at least one, and no more
  // than it takes to reach `max_points` points and streamlines (so at most max_points - 1 plus one
  // streamline). Returns false, with no streamline in `batch`, at the end of the data. Also returns false,
  // with overflowed() set, once `batch` holds more than `max_points_held` points (a streamline too long
  // to hold whole; checked per read buffer, so it may hold one buffer more); rewind() to go on.
  bool next(Tractogram& batch, std::uint64_t max_points, std::uint64_t max_points_held = ~std::uint64_t(0));
  bool overflowed() const { return overflowed_; }

 private:
  bool fill_buffer();  // reads the next chunk; false at the end of the file
  void read_at(std::uint64_t offset, std::uint8_t* dst, std::uint64_t size);
  void check_unchanged() const;

  std::string path_;
  int fd_ = -1;
  MrtrixHeader header_;
  MrtrixDatatype datatype_ = MrtrixDatatype::kFloat32LE;  // header_.datatype
  SourceInfo source_;
  std::uint32_t triplet_bytes_ = 12;
  std::int64_t mtime_ns_ = 0;
  std::uint64_t window_bytes_ = 0;          // the size of each part of the file read (a whole number of triplets)
  std::unique_ptr<std::uint8_t[]> window_;  // the part being decoded
  std::uint64_t buffer_used_ = 0, buffer_size_ = 0;  // consumed / valid bytes of window_
  std::uint64_t read_end_ = 0;                       // file offset just after window_'s valid bytes
  tck::DecodeState state_;
  bool data_ended_ = false;
  bool overflowed_ = false;
  std::uint64_t streamlines_ = 0;  // closed in this pass
  bool complete_ = false;
  std::unique_ptr<Xxh3_128Stream> hash_;  // while the first pass runs
};

}  // namespace vxl
