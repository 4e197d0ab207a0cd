// Direct writes (DirectRegionWriter): regions that start and end anywhere, appended in pieces of any size
// through a small staging buffer, must give exactly the bytes of plain writes — with O_DIRECT where the
// file system allows it, and without it. And a streaming conversion whose limit turns direct writes on
// must still write the in-memory conversion's bytes, whether it holds VERT or writes it block by block.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/convert/convert.h"
#include "converter/convert/streaming_convert.h"
#include "converter/export/tck_writer.h"
#include "converter/readers/read_tractogram.h"
#include "converter/synth/synth.h"
#include "format/base/atomic_output.h"
#include "format/base/direct_region_writer.h"
#include "format/base/direct_write_queue.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

// Regions back to back (the first from offset 0), of sizes below, at and across block boundaries. With
// `from_blocks`, most pieces are appended from a block-aligned buffer laid out as append_from_block wants.
void write_regions(const std::string& path, bool use_direct_io, const std::vector<std::uint8_t>& expected,
                   const std::vector<std::uint64_t>& ends, bool from_blocks) {
  AtomicOutputFile out(path);
  out.allocate(expected.size());
  const int direct_fd = use_direct_io ? out.direct_descriptor() : -1;
  std::mt19937 rng(5);
  constexpr std::uint64_t block = DirectRegionWriter::kBlock;
  std::unique_ptr<std::uint8_t, void (*)(void*)> buffer(
      static_cast<std::uint8_t*>(std::aligned_alloc(block, (20000 + 2 * block) / block * block)), std::free);
  ASSERT_NE(buffer, nullptr);
  std::uint64_t start = 0;
  for (std::size_t r = 0; r < ends.size(); ++r) {
    const std::uint64_t end = ends[r];
    DirectRegionWriter region(out, direct_fd, start, end - start, 3 * block);
    // Pieces from blocks two times in three, the pattern shifted per region: a region's first piece, and
    // pieces back to back, come from blocks too.
    std::size_t piece = r;
    for (std::uint64_t at = start; at < end; ++piece) {
      const std::uint64_t n =
          std::min<std::uint64_t>(end - at, std::uniform_int_distribution<std::uint64_t>(1, 20000)(rng));
      if (from_blocks && piece % 3 != 0) {
        std::fill_n(buffer.get(), block, std::uint8_t{0xEE});  // what precedes the bytes is the writer's
        std::copy_n(expected.data() + at, n, buffer.get() + region.block_lead());
        region.append_from_block(buffer.get(), n);
      } else {
        region.append({expected.data() + at, n});
      }
      at += n;
    }
    start = end;
  }
  out.commit();
}

// 600000 random bytes written as regions ending at `ends`, with O_DIRECT and without: the plain bytes both ways.
void expect_plain_bytes(const ScratchDir& dir, std::uint32_t seed, const std::vector<std::uint64_t>& ends,
                        bool from_blocks) {
  std::mt19937 rng(seed);
  std::vector<std::uint8_t> expected(600000);
  for (auto& b : expected) b = static_cast<std::uint8_t>(rng());
  for (bool direct : {true, false}) {
    const std::string path = dir.file(direct ? "direct.bin" : "buffered.bin");
    write_regions(path, direct, expected, ends, from_blocks);
    EXPECT_TRUE(test::slurp<std::vector<std::uint8_t>>(path) == expected)
        << (direct ? "with" : "without") << " O_DIRECT";
  }
}

TEST(DirectWrites, RegionsOfAnySizeAppendedInPiecesGiveThePlainBytes) {
  ScratchDir dir;
  const std::uint64_t block = DirectRegionWriter::kBlock;
  expect_plain_bytes(dir, 3,
                     {7, block - 1, block, block + 1, 5 * block + 100, 9 * block, 9 * block + 4, 120000,
                      40 * block + 13, 599999, 600000},
                     false);
  AtomicOutputFile probe(dir.file("probe.bin"));
  if (probe.direct_descriptor() < 0)
    GTEST_LOG_(INFO) << "this file system refuses O_DIRECT: only the fallback was exercised";
}

TEST(DirectWrites, RegionsAppendedFromBlocksGiveThePlainBytes) {
  ScratchDir dir;
  const std::uint64_t block = DirectRegionWriter::kBlock;
  expect_plain_bytes(dir, 4, {5, block + 3, 3 * block, 7 * block + 1, 130001, 599000, 600000}, true);
}

// All regions open at once and appended in a random interleaving (as the placing pass appends to the
// vertex blocks), their full stagings handed to a write queue and swapped for its spares: with no spare
// (each submit waits for its own buffer to come back) and with a few, with and without O_DIRECT.
TEST(DirectWrites, RegionsInterleavedThroughAWriteQueueGiveThePlainBytes) {
  ScratchDir dir;
  std::mt19937 rng(7);
  std::vector<std::uint8_t> expected(600000);
  for (auto& b : expected) b = static_cast<std::uint8_t>(rng());
  const std::uint64_t block = DirectRegionWriter::kBlock, staging = 3 * block;
  const std::vector<std::uint64_t> ends = {7,         block - 1,     block,  block + 1,       5 * block + 100,
                                           9 * block, 9 * block + 4, 120000, 40 * block + 13, 599999,
                                           600000};
  for (bool direct : {true, false}) {
    for (std::uint64_t spare_count : {0, 3}) {
      SCOPED_TRACE(std::string(direct ? "with" : "without") + " O_DIRECT, " + std::to_string(spare_count) + " spares");
      const std::string path = dir.file("queued.bin");
      AtomicOutputFile out(path);
      out.allocate(expected.size());
      const int direct_fd = direct ? out.direct_descriptor() : -1;
      // The caller's memory: the spares, then each region's staging.
      std::uint64_t memory_bytes = spare_count * staging, start = 0;
      for (std::uint64_t end : ends)
        memory_bytes += DirectRegionWriter::staging_size(end - start, staging), start = end;
      std::unique_ptr<std::uint8_t, void (*)(void*)> memory(
          static_cast<std::uint8_t*>(std::aligned_alloc(block, memory_bytes)), std::free);
      std::uint8_t* next = memory.get();
      std::vector<std::uint8_t*> spares;
      for (std::uint64_t k = 0; k < spare_count; ++k, next += staging) spares.push_back(next);
      DirectWriteQueue queue(out, direct_fd, spares, staging);
      std::vector<std::unique_ptr<DirectRegionWriter>> regions;
      std::vector<std::uint64_t> at, region_end;
      start = 0;
      for (std::uint64_t end : ends) {
        regions.push_back(
            std::make_unique<DirectRegionWriter>(out, direct_fd, start, end - start, staging, next, &queue));
        next += DirectRegionWriter::staging_size(end - start, staging);
        at.push_back(start);
        region_end.push_back(end);
        start = end;
      }
      for (std::size_t open = regions.size(); open > 0;) {
        const std::size_t r = std::uniform_int_distribution<std::size_t>(0, regions.size() - 1)(rng);
        if (at[r] == region_end[r]) continue;
        const std::uint64_t n =
            std::min<std::uint64_t>(region_end[r] - at[r], std::uniform_int_distribution<std::uint64_t>(1, 5000)(rng));
        regions[r]->append({expected.data() + at[r], n});
        at[r] += n;
        if (at[r] == region_end[r]) --open;
      }
      queue.finish();
      out.commit();
      EXPECT_TRUE(test::slurp<std::vector<std::uint8_t>>(path) == expected);
    }
  }
}

// Under a limit that turns direct writes on, VERT is written block by block as it is placed and read back
// for the orders where its (voxel, level) blocks are few (10 mm voxels; asked for, as VERT would fit whole), and
// held in memory where their staging would not fit (1 mm voxels: hundreds of thousands of blocks); packed or
// float32, each way must write the bytes of a conversion from memory.
TEST(DirectWrites, AStreamingConversionWithDirectWritesWritesTheInMemoryBytes) {
  ScratchDir dir;
  const std::string tck = dir.file("in.tck"), whole = dir.file("whole.vxl"), direct = dir.file("direct.vxl");
  Tractogram t = synthesize_tractogram({20000, 2});
  {
    TckWriter w(tck, t.streamline_count());
    for (std::uint64_t i = 0; i < t.streamline_count(); ++i)
      w.add({t.positions.data() + 3 * t.offsets[i], 3 * (t.offsets[i + 1] - t.offsets[i])});
    w.finish();
  }
  struct Case {
    PositionEncoding positions;
    double voxel_size;
    bool read_back;
  };
  for (const Case c : {Case{PositionEncoding::Packed, 10.0, true}, Case{PositionEncoding::Float32, 10.0, true},
                       Case{PositionEncoding::Packed, 1.0, false}, Case{PositionEncoding::Float32, 1.0, false}}) {
    SCOPED_TRACE(std::string(c.positions == PositionEncoding::Packed ? "packed" : "float32") + ", " +
                 std::to_string(c.voxel_size) + " mm");
    ConvertSettings settings;
    settings.threads = 2;
    settings.positions = c.positions;
    settings.voxel_size = c.voxel_size;
    convert_tractogram(read_tractogram(tck), whole, settings);
    settings.memory_limit = 512ull << 20;  // at least 256 MiB: direct writes
    // The whole orders at once, and 64 KiB at a time: then VERT is read back in many parts, each
    // starting inside a disk block, the next one read while the orders of this one are built.
    for (const std::uint64_t chunk : {std::uint64_t{0}, std::uint64_t{64} << 10}) {
      SCOPED_TRACE("orders chunk " + std::to_string(chunk));
      StreamingTuning tuning;
      tuning.order_chunk_bytes = chunk;
      tuning.vertex_blocks = true;
      const ConvertSummary s = convert_streaming(tck, direct, settings, tuning);
      EXPECT_EQ(s.vertices_read_back, c.read_back);
      const std::vector<std::uint8_t> a = test::slurp<std::vector<std::uint8_t>>(whole),
                                      b = test::slurp<std::vector<std::uint8_t>>(direct);
      EXPECT_GT(a.size(), 1000000u);
      EXPECT_TRUE(a == b) << "the conversion with direct writes differs (" << a.size() << " vs " << b.size()
                          << " bytes)";
    }
  }
}

}  // namespace
}  // namespace vxl
