// Packed vertex positions (spec §5.4): 10 bits per axis across each voxel's tight bounds. The stated error
// bound must hold at the extremes — degenerate, tiny and huge boxes, far from the origin — both for the
// codec alone and for whole conversions; verify must check the voxline-end bit; the CLI chooses.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "converter/convert/convert.h"
#include "format/vxl_file.h"
#include "format/vxl_positions.h"
#include "format/vxl_streamlines.h"
#include "format/vxl_verify.h"
#include "tests/reseal_checksums.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::run_cli;
using test::ScratchDir;
using test::slurp;

// A voxel entry whose tight bounds are the cube [lo, lo + extent] (only the bounds matter to the codec).
VoxelEntry box(double lo, double extent) {
  VoxelEntry v{};
  for (int c = 0; c < 3; ++c) {
    v.tight_min[c] = static_cast<float>(lo + c * extent / 7);  // a different corner per axis
    v.tight_max[c] = static_cast<float>(double(v.tight_min[c]) + extent);
  }
  return v;
}

TEST(PackedPositions, EveryPointDecodesWithinTheBoundAtTheExtremes) {
  std::mt19937 rng(11);
  int boxes = 0;
  for (double lo : {0.0, -50.0, 1e5, -1e5, 3e7})
    for (double extent : {0.0, 1e-6, 1e-3, 1.0, 10.0, 1e3, 1e5}) {
      const VoxelEntry v = box(lo, extent);
      // Corners, then random points inside the box (floats, as the converter has them).
      std::vector<float> exact;
      for (int corner = 0; corner < 8; ++corner)
        for (int c = 0; c < 3; ++c) exact.push_back((corner >> c) & 1 ? v.tight_max[c] : v.tight_min[c]);
      for (int i = 0; i < 500; ++i)
        for (int c = 0; c < 3; ++c) {
          const float t = std::uniform_real_distribution<float>(0, 1)(rng);
          exact.push_back(
              std::clamp(v.tight_min[c] + t * (v.tight_max[c] - v.tight_min[c]), v.tight_min[c], v.tight_max[c]));
        }
      const std::uint32_t n = static_cast<std::uint32_t>(exact.size() / 3);
      std::vector<float> decoded = exact;
      std::vector<std::uint32_t> words(n);
      pack_block(v, decoded.data(), n, words.data());
      std::vector<float> again(3 * n);
      unpack_block(v, words.data(), n, again.data());
      SCOPED_TRACE("lo " + std::to_string(lo) + ", extent " + std::to_string(extent));
      ASSERT_EQ(std::memcmp(again.data(), decoded.data(), 4 * again.size()), 0)
          << "pack_block's decoded values must be what unpack_block gives";
      const double bound = packed_error_bound(v);
      double worst = 0;
      for (std::size_t k = 0; k < exact.size(); ++k) worst = std::max(worst, std::abs(double(decoded[k]) - exact[k]));
      EXPECT_LE(worst, bound);
      for (std::uint32_t w : words) EXPECT_EQ(w & ~0x3FFFFFFFu, 0u) << "only the 30 coordinate bits";
      // The corner at the minimum decodes exactly; a degenerate box decodes every point exactly.
      EXPECT_EQ(std::memcmp(decoded.data(), exact.data(), 12), 0);
      if (extent == 0) {
        EXPECT_EQ(worst, 0.0);
      }
      // The bound is not a loose multiple of the real error: 500 random points come close to it, where the
      // steps are coarser than the floats there (else every float in the box decodes exactly).
      const double ulp = std::ldexp(std::max(std::abs(lo), std::abs(lo + extent)), -23);
      if (extent >= 1.0 && extent / kPackedSteps > 16 * ulp) {
        EXPECT_GT(worst, bound / 8);
      }
      ++boxes;
    }
  EXPECT_EQ(boxes, 35);
}

// Streamlines with steps of about 1.3 mm, scaled by `scale` and moved by `offset`.
Tractogram scaled_tractogram(double scale, double offset) {
  Tractogram t;
  t.source.path = "scaled.tck";
  std::mt19937 rng(5);
  std::normal_distribution<float> jitter(0, 0.4f);
  for (int s = 0; s < 20; ++s) {
    std::vector<float> pts;
    float p[3] = {float(s % 5), float(s / 5), 0};
    for (int i = 0; i < 25; ++i) {
      p[0] += 1.0f + jitter(rng);
      p[1] += 0.5f * jitter(rng);
      p[2] += 0.7f + jitter(rng);
      for (float c : p) pts.push_back(static_cast<float>(offset + scale * c));
    }
    t.add_streamline(pts.data(), 25);
  }
  return t;
}

struct Extreme {
  const char* name;
  double scale, offset, voxel_size;
};

class PackedConversion : public ::testing::TestWithParam<Extreme> {};

// Whole conversions: every source point comes back (through the walk, i.e. `export`) within the largest
// bound of the file's voxels, and verify accepts the file (its orders are sorted for the decoded positions).
// The spec's q = round((x - lo) / step), computed as the quotient itself.
std::uint32_t spec_q(double x, float lo, float step) {
  if (!(step > 0)) return 0;
  const double t = (x - double(lo)) / double(step);
  return t <= 0 ? 0 : t >= kPackedSteps ? kPackedSteps : static_cast<std::uint32_t>(std::floor(t + 0.5));
}

// The packer truncates t + 0.5 where the spec rounds (floor): it must give the spec's q everywhere, above
// all at the half-steps where rounding turns, at the bounds, and for boxes tiny, huge and far from the
// origin; words() (no decoding) must give pack()'s words.
TEST(PackedPositions, ThePackerRoundsExactlyLikeTheSpecsQuotient) {
  std::mt19937 rng(23);
  std::uint64_t points = 0, half_steps = 0;
  for (double lo : {0.0, -1.0, 12.5, -300.0, 1.0e6, -3.0e7}) {
    for (double extent : {1.0e-5, 0.37, 10.0, 1234.5, 8.0e6}) {
      const VoxelEntry v = box(lo, extent);
      const VertexPacker packer(v);
      for (int c = 0; c < 3; ++c) {
        const float vlo = v.tight_min[c], step = (v.tight_max[c] - v.tight_min[c]) / float(kPackedSteps);
        std::vector<float> xs = {v.tight_min[c], v.tight_max[c]};
        // Every half-step (the float nearest it and its neighbours), where q changes.
        for (std::uint32_t k = 0; k < kPackedSteps; ++k) {
          const float half = static_cast<float>(double(vlo) + (double(k) + 0.5) * double(step));
          xs.insert(xs.end(), {std::nextafter(half, -INFINITY), half, std::nextafter(half, INFINITY)});
        }
        std::uniform_real_distribution<double> inside(v.tight_min[c], v.tight_max[c]);
        for (int i = 0; i < 3000; ++i) xs.push_back(static_cast<float>(inside(rng)));
        // Outside the box (clamped to 0 and kPackedSteps).
        xs.insert(xs.end(), {std::nextafter(v.tight_min[c], -INFINITY), v.tight_min[c] - 1000 * step,
                             std::nextafter(v.tight_max[c], INFINITY), v.tight_max[c] + 1000 * step});
        // words() over many vertices at once gives each one's word.
        std::vector<float> many;
        for (float x : xs)
          many.insert(many.end(), {v.tight_min[0], v.tight_min[1], v.tight_min[2]}), many[many.size() - 3 + c] = x;
        std::vector<std::uint32_t> many_words(xs.size());
        packer.words(many.data(), xs.size(), many_words.data());
        for (std::size_t i = 0; i < xs.size(); ++i) ASSERT_EQ(many_words[i], packer.pack(many.data() + 3 * i)) << i;
        for (float x : xs) {
          float xyz[3] = {v.tight_min[0], v.tight_min[1], v.tight_min[2]};
          xyz[c] = x;
          std::uint32_t only_words = 0;
          packer.words(xyz, 1, &only_words);
          const std::uint32_t word = packer.pack(xyz);
          ASSERT_EQ(only_words, word);
          ASSERT_EQ((word >> (10 * c)) & kPackedAxisMask, spec_q(x, vlo, step))
              << "x " << x << " in [" << v.tight_min[c] << ", " << v.tight_max[c] << "]";
          ++points;
        }
        half_steps += kPackedSteps;
      }
    }
  }
  EXPECT_GT(half_steps, 90000u);
  EXPECT_GT(points, 500000u);
  // A box flat along an axis (step 0): that axis's quantum is 0, the others as in a full box.
  VoxelEntry flat = box(-4.0, 2.0);
  flat.tight_max[1] = flat.tight_min[1];
  const VertexPacker packer(flat);
  float xyz[6] = {-3.0f, flat.tight_min[1], -2.5f, -2.1f, flat.tight_min[1], -4.0f};
  std::uint32_t words[2];
  packer.words(xyz, 2, words);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ((words[i] >> 10) & kPackedAxisMask, 0u);
    EXPECT_EQ(words[i], packer.pack(xyz + 3 * i));
  }
}

TEST_P(PackedConversion, EveryPointComesBackWithinTheBound) {
  const Extreme e = GetParam();
  ScratchDir dir;
  Tractogram source = scaled_tractogram(e.scale, e.offset);
  const std::vector<float> expected = source.positions;
  ConvertSettings settings;
  settings.voxel_size = e.voxel_size;
  convert_tractogram(std::move(source), dir.file("p.vxl"), settings);
  const VerifyResult verified = verify_vxl(dir.file("p.vxl"));
  ASSERT_TRUE(verified.valid) << verified.problem;
  const VxlFile f = VxlFile::open(dir.file("p.vxl"));
  ASSERT_EQ(f.position_encoding(), PositionEncoding::Packed);
  double bound = 0;
  for (const VoxelEntry& v : f.voxels()) bound = std::max(bound, packed_error_bound(v));
  std::vector<float> got;
  walk_streamlines(
      f, {[&](std::uint64_t, std::span<const float> xyz) { got.insert(got.end(), xyz.begin(), xyz.end()); }, {}, {}});
  ASSERT_EQ(got.size(), expected.size());
  double worst = 0;
  for (std::size_t k = 0; k < got.size(); ++k) worst = std::max(worst, std::abs(double(got[k]) - expected[k]));
  EXPECT_LE(worst, bound) << f.meta().voxel_count << " voxels";
  // The bound follows the voxel, not the scene: at most the voxel's extent (plus a step on each side
  // for the connecting vertices) / 2046, plus the rounding of coordinates this far out.
  const double step = 1.3 * e.scale * 3;
  EXPECT_LE(bound, (e.voxel_size + 2 * step) * (1.0 / 2046 + 1e-6) +
                       std::ldexp(1.0, -23) * (std::abs(e.offset) + 40 * e.scale) * 1.01);
}

INSTANTIATE_TEST_SUITE_P(Extremes, PackedConversion,
                         ::testing::Values(Extreme{"tiny_voxels", 0.01, 0, 0.004}, Extreme{"brain", 1, 0, 10},
                                           Extreme{"huge_voxels", 1, 0, 5000}, Extreme{"far_from_origin", 1, 1e5, 10},
                                           Extreme{"far_and_tiny", 0.01, -1e4, 0.05},
                                           Extreme{"planet_scale", 1e4, 0, 2e4}),
                         [](const ::testing::TestParamInfo<Extreme>& info) { return std::string(info.param.name); });

// verify checks every packed word's voxline-end bit against the voxline table, and the reserved bit.
TEST(PackedPositions, VerifyRefusesAWrongVoxlineEndOrReservedBit) {
  ScratchDir dir;
  ConvertSettings settings;
  settings.voxel_size = 8;
  convert_tractogram(scaled_tractogram(1, 0), dir.file("p.vxl"), settings);
  ASSERT_TRUE(verify_vxl(dir.file("p.vxl")).valid);
  const VxlFile f = VxlFile::open(dir.file("p.vxl"));
  const std::uint64_t vert = f.find_section(section_id("VERT"))->offset;
  for (std::uint32_t bit : {kPackedVoxlineEnd, kPackedReservedBit})
    for (std::uint64_t vertex : {std::uint64_t(0), f.meta().vertex_count - 1}) {
      std::vector<char> bytes = slurp(dir.file("p.vxl"));
      std::uint32_t word;
      std::memcpy(&word, bytes.data() + vert + 4 * vertex, 4);
      word ^= bit;
      std::memcpy(bytes.data() + vert + 4 * vertex, &word, 4);
      ASSERT_TRUE(test::reseal_checksums(bytes.data(), bytes.size()));
      test::write_file(dir.file("bad.vxl"), bytes);
      const VerifyResult r = verify_vxl(dir.file("bad.vxl"));
      EXPECT_FALSE(r.valid) << "bit " << bit << " of vertex " << vertex;
      EXPECT_NE(r.problem.find("packed vertex " + std::to_string(vertex) + ": voxline-end bit wrong or reserved bit"),
                std::string::npos)
          << r.problem;
    }
}

// The command line: packed by default (version 2.0, 4 bytes a vertex), float32 on request (version 1.0,
// the source's bits), an unknown name refused as a usage error; info names the encoding and the bound.
TEST(PackedPositions, ConvertChoosesTheEncodingAndInfoStatesIt) {
  ScratchDir dir;
  ASSERT_EQ(run_cli("synth " + dir.file("s.tck") + " --streamlines 200").exit_code, 0);
  ASSERT_EQ(run_cli("convert " + dir.file("s.tck") + " " + dir.file("packed.vxl")).exit_code, 0);
  ASSERT_EQ(run_cli("convert " + dir.file("s.tck") + " " + dir.file("exact.vxl") + " --positions float32 --levels 1")
                .exit_code,
            0);
  const VxlFile packed = VxlFile::open(dir.file("packed.vxl")), exact = VxlFile::open(dir.file("exact.vxl"));
  EXPECT_EQ(packed.header().version_major, 2);
  EXPECT_EQ(exact.header().version_major, 1);  // float32 positions and one level: the 1.x file
  EXPECT_EQ(packed.find_section(section_id("VERT"))->size * 3, exact.find_section(section_id("VERT"))->size);
  EXPECT_LT(packed.bytes().size(), exact.bytes().size());
  const auto info = run_cli("info " + dir.file("packed.vxl"));
  EXPECT_NE(info.output.find("positions     packed (10 bits per axis per voxel; error at most"), std::string::npos)
      << info.output;
  EXPECT_NE(run_cli("info " + dir.file("exact.vxl")).output.find("positions     float32 (exact)"), std::string::npos);
  const auto bad = run_cli("convert " + dir.file("s.tck") + " " + dir.file("bad.vxl") + " --positions half");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--positions"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace vxl
