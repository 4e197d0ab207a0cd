// The voxline and streamline tables (VXLN, STRM) appended as the first range is placed, a buffer at a time,
// each buffer written on a thread of its own while the next one fills: the placing thread does not wait on
// the disk. (Appended from the placing thread itself, each 2 MB of direct writes put it to sleep until the disk
// answered: 750 MB of tables on a 10M-streamline source.)
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "format/base/parallel.h"
#include "format/vxl_stream_writer.h"

namespace vxl::streaming {

class TableAppender {
 public:
  // Buffers of `entries` entries of each table, two of them (filling and being written).
  TableAppender(VxlStreamWriter& out, std::size_t entries);
  TableAppender(const TableAppender&) = delete;
  TableAppender& operator=(const TableAppender&) = delete;

  // The next STRM entry (a streamline's first voxline) and the next VXLN entry.
  void add_streamline(std::uint64_t first_voxline) {
    filling_.streamlines.push_back(first_voxline);
    if (filling_.streamlines.size() == entries_) write_filled();
  }
  void add_voxline(const VoxlineEntry& e) {
    filling_.voxlines.push_back(e);
    if (filling_.voxlines.size() == entries_) write_filled();
  }
  // Writes what is left and waits for every write. Rethrows a failed write (as the calls above may).
  void finish();

 private:
  struct Buffers {
    std::vector<VoxlineEntry> voxlines;
    std::vector<std::uint64_t> streamlines;
  };
  // Starts writing the filled buffers once the earlier write is done; the other buffers fill meanwhile.
  void write_filled();
  void append(const Buffers& b);

  VxlStreamWriter& out_;
  std::size_t entries_;
  Buffers filling_, writing_;
  BackgroundTask<> write_;
};

}  // namespace vxl::streaming
