// Virtual dissection (voxlines select): the voxel-indexed query against a brute-force reference that tests
// every source point of every streamline, on random spheres, boxes and masks (an oblique affine among
// them), exclude and ends-only regions, length limits and their inverse; tckedit's containment rules at the
// edges (a point on a sphere, a zero radius, rounding to the nearest mask voxel); the outputs (TCK, TRX with
// groups and values, VTK, VXL, and empty ones); packed positions' flips counted and explained; hostile
// region arguments refused with nothing written.
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <tuple>

#include <sys/resource.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include "converter/convert/convert.h"
#include "converter/export/streamline_outputs.h"
#include "converter/readers/read_tractogram.h"
#include "converter/readers/volume_image.h"
#include "converter/selection/length_limits.h"
#include "converter/selection/region.h"
#include "converter/selection/selection_output.h"
#include "converter/selection/streamline_selection.h"
#include "converter/selection/voxline_boxes.h"
#include "converter/synth/synth.h"
#include "format/base/error.h"
#include "format/level_voxlines.h"
#include "format/vxl_verify.h"
#include "tests/address_sanitizer.h"
#include "tests/hostile_inputs.h"
#include "tests/hostile_vxl.h"
#include "tests/mif_test_files.h"
#include "tests/nifti_test_files.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::run_cli;
using test::ScratchDir;

Tractogram synth(std::uint64_t n, std::uint64_t seed = 7) {
  SynthSettings s;
  s.streamlines = n;
  s.seed = seed;
  return synthesize_tractogram(s);
}

ConvertSettings settings(PositionEncoding positions, double voxel_size = 10.0) {
  ConvertSettings s;
  s.positions = positions;
  s.voxel_size = voxel_size;
  s.threads = 2;
  return s;
}

// The reference: every point of every streamline of the source tested against every region.
std::vector<std::uint64_t> brute_force(const Tractogram& t, const SelectionCriteria& c) {
  std::vector<std::uint64_t> kept;
  for (std::uint64_t s = 0; s < t.streamline_count(); ++s) {
    const std::uint64_t first = t.offsets[s], last = t.offsets[s + 1];
    auto point = [&](std::uint64_t i) { return &t.positions[3 * i]; };
    auto anywhere = [&](const Region& r) {
      for (std::uint64_t i = first; i < last; ++i)
        if (r.contains(point(i))) return true;
      return false;
    };
    bool pass = std::all_of(c.include.begin(), c.include.end(), anywhere) &&
                std::none_of(c.exclude.begin(), c.exclude.end(), anywhere);
    for (const Region& r : c.ends_in)
      pass = pass && last > first && (r.contains(point(first)) || r.contains(point(last - 1)));
    if (c.min_length || c.max_length) {
      // tckedit's float32 sum, Eigen's order for a segment: x² + (y² + z²).
      float length = 0;
      for (std::uint64_t i = first + 1; i < last; ++i) {
        const float dx = point(i)[0] - point(i - 1)[0], dy = point(i)[1] - point(i - 1)[1],
                    dz = point(i)[2] - point(i - 1)[2];
        const float yz = dy * dy + dz * dz;
        length += std::sqrt(dx * dx + yz);
      }
      pass =
          pass && !(c.min_length && length < float(*c.min_length)) && !(c.max_length && length > float(*c.max_length));
    }
    if (pass != c.invert) kept.push_back(s);
  }
  return kept;
}

Region sphere(float x, float y, float z, float r) {
  return parse_region(std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(z) + "," + std::to_string(r));
}

// A label map over the synthetic brain: 2 mm voxels turned 30 degrees about z and 10 about x (an oblique
// affine), labels 1 and 2 in two random blobs, 0 elsewhere.
std::string write_oblique_labels(const ScratchDir& dir, std::mt19937& rng) {
  const std::array<std::int64_t, 3> dims{90, 100, 80};
  const double a = 30 * M_PI / 180, b = 10 * M_PI / 180, s = 2.0;
  // R = Rz(a) * Rx(b), scaled by s; voxel (45, 50, 40) at the synthetic centre.
  const double r[3][3] = {{std::cos(a), -std::sin(a) * std::cos(b), std::sin(a) * std::sin(b)},
                          {std::sin(a), std::cos(a) * std::cos(b), -std::cos(a) * std::sin(b)},
                          {0, std::sin(b), std::cos(b)}};
  std::array<double, 12> m{};
  for (int row = 0; row < 3; ++row) {
    double t = kSynthCentre[row];
    for (int col = 0; col < 3; ++col) {
      m[4 * row + col] = s * r[row][col];
      t -= s * r[row][col] * (col == 0 ? 45 : col == 1 ? 50 : 40);
    }
    m[4 * row + 3] = t;
  }
  std::uniform_int_distribution<int> ci(20, 70), cj(20, 80), ck(15, 65);
  const int centres[2][3] = {{ci(rng), cj(rng), ck(rng)}, {ci(rng), cj(rng), ck(rng)}};
  std::vector<std::int16_t> values(std::size_t(dims[0] * dims[1] * dims[2]), 0);
  for (std::int64_t k = 0; k < dims[2]; ++k)
    for (std::int64_t j = 0; j < dims[1]; ++j)
      for (std::int64_t i = 0; i < dims[0]; ++i)
        for (int l = 0; l < 2; ++l) {
          const double d2 =
              std::pow(i - centres[l][0], 2) + std::pow(j - centres[l][1], 2) + std::pow(k - centres[l][2], 2);
          if (d2 < 36 + 20 * std::sin(double(i + 2 * j + 3 * k)))  // a lumpy blob, ~6 voxels across
            values[std::size_t((k * dims[1] + j) * dims[0] + i)] = std::int16_t(l + 1);
        }
  const std::string path = dir.file("labels.nii.gz");
  test::write_nifti_int16(path, dims, values, m);
  return path;
}

class Selection : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    source_ = new Tractogram(synth(3000));
    dir_ = new ScratchDir();
    Tractogram copy = *source_;
    convert_tractogram(std::move(copy), dir_->file("f32.vxl"), settings(PositionEncoding::Float32));
    copy = *source_;
    convert_tractogram(std::move(copy), dir_->file("f32_4mm.vxl"), settings(PositionEncoding::Float32, 4.0));
    copy = *source_;
    convert_tractogram(std::move(copy), dir_->file("packed_4mm.vxl"), settings(PositionEncoding::Packed, 4.0));
  }
  static void TearDownTestSuite() {
    delete source_;
    delete dir_;
  }
  static Tractogram* source_;
  static ScratchDir* dir_;
};
Tractogram* Selection::source_ = nullptr;
ScratchDir* Selection::dir_ = nullptr;

TEST_F(Selection, RandomSpheresBoxesAndMasksMatchTheBruteForceReference) {
  std::mt19937 rng(11);
  const std::string labels = write_oblique_labels(*dir_, rng);
  // Regions near random source points (anywhere in the bounds, most would hold nothing).
  std::uniform_int_distribution<std::uint64_t> point(0, source_->point_count() - 1);
  std::uniform_real_distribution<float> jitter(-10, 10), radius(0, 25), side(2, 40);
  auto near_a_point = [&] {
    const float* p = &source_->positions[3 * point(rng)];
    return std::array<float, 3>{p[0] + jitter(rng), p[1] + jitter(rng), p[2] + jitter(rng)};
  };
  auto random_sphere = [&] {
    const auto c = near_a_point();
    return sphere(c[0], c[1], c[2], radius(rng));
  };
  auto random_box = [&] {
    const auto c = near_a_point();
    const float x0 = c[0] - 10, y0 = c[1] - 10, z0 = c[2] - 10;
    return parse_region("box:" + std::to_string(x0) + "," + std::to_string(y0) + "," + std::to_string(z0) + "," +
                        std::to_string(x0 + side(rng)) + "," + std::to_string(y0 + side(rng)) + "," +
                        std::to_string(z0 + side(rng)));
  };
  auto random_region = [&](int kind) {
    return kind == 0 ? random_sphere() : kind == 1 ? random_box() : parse_region(labels + (kind == 2 ? ":1" : ":2"));
  };
  int nonempty = 0, cases = 0;
  std::map<std::string, std::optional<VoxelVoxlines>> index;
  for (const char* file : {"f32.vxl", "f32_4mm.vxl"}) {
    const VxlFile f = VxlFile::open(dir_->file(file));
    index[file] = VoxelVoxlines::build(f);
    ASSERT_TRUE(index[file].has_value());
    for (int trial = 0; trial < 40; ++trial) {
      SelectionCriteria c;
      c.include.push_back(random_region(trial % 4));
      if (trial % 3 == 1) c.include.push_back(random_region((trial + 1) % 4));
      if (trial % 5 == 2) c.exclude.push_back(random_region((trial + 2) % 2));
      if (trial % 7 == 3) c.ends_in.push_back(random_region(trial % 2));
      if (trial % 6 == 4) c.min_length = 60;
      if (trial % 8 == 5) c.max_length = 120;
      c.invert = trial % 9 == 6;
      const SelectionResult r = select_streamlines(f, c);
      ASSERT_EQ(r.streamlines, brute_force(*source_, c)) << file << " trial " << trial;
      // Through an index built from the tables, and by the scan of the voxline table: the same streamlines, the
      // same count per region as through the file's own index.
      const SelectionResult indexed = select_streamlines(f, c, &*index.at(file)),
                            scan = select_streamlines(f, c, nullptr, SelectionPath::ScanTable);
      ASSERT_EQ(indexed.streamlines, r.streamlines) << file << " trial " << trial;
      ASSERT_EQ(indexed.streamlines_per_region, r.streamlines_per_region) << file << " trial " << trial;
      ASSERT_EQ(scan.streamlines, r.streamlines) << file << " trial " << trial;
      ASSERT_EQ(scan.streamlines_per_region, r.streamlines_per_region) << file << " trial " << trial;
      nonempty += !r.streamlines.empty() && r.streamlines.size() < source_->streamline_count();
      ++cases;
    }
  }
  // The random regions must mostly cut the set, or the comparison says little.
  EXPECT_GT(nonempty, cases / 3);
}

// The table of hits keeps a byte a streamline for each 8 regions: with any number of regions (one byte, several),
// each region's count is what it selects alone, and the streamlines kept are the reference's.
TEST_F(Selection, EachRegionCountsAsItSelectsAloneWhateverTheNumberOfRegions) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::uint64_t> point(0, source_->point_count() - 1);
  std::uniform_real_distribution<float> radius(5, 30);
  for (const char* file : {"f32.vxl", "packed_4mm.vxl"}) {
    const VxlFile f = VxlFile::open(dir_->file(file));
    for (const std::size_t regions : {1u, 2u, 3u, 5u, 9u, 17u, 33u, 64u}) {
      SelectionCriteria c;
      for (std::size_t r = 0; r < regions; ++r) {
        const float* p = &source_->positions[3 * point(rng)];
        (r % 2 == 0 ? c.include : c.exclude).push_back(sphere(p[0], p[1], p[2], radius(rng)));
      }
      const SelectionResult all = select_streamlines(f, c);
      ASSERT_EQ(all.streamlines, brute_force(*source_, c)) << file << ", " << regions << " regions";
      ASSERT_EQ(all.streamlines_per_region.size(), regions);
      std::vector<Region> in_order = c.include;  // the counts' order: the includes, then the excludes
      in_order.insert(in_order.end(), c.exclude.begin(), c.exclude.end());
      for (std::size_t r = 0; r < regions; ++r) {
        SelectionCriteria alone;
        alone.include.push_back(in_order[r]);
        EXPECT_EQ(all.streamlines_per_region[r], select_streamlines(f, alone).streamlines.size())
            << file << ", region " << r << " of " << regions;
      }
    }
  }
}

// A packed file's points are tested where they lie in its words, each region's window of quanta first; the scan of
// the voxline table decodes every point it tests. Both must find the same points in every kind of region, the
// spheres' surfaces included: spheres centred on points, radii ending on points.
TEST_F(Selection, OnAPackedFileTheIndexAndTheScanFindTheSamePoints) {
  const VxlFile f = VxlFile::open(dir_->file("packed_4mm.vxl"));
  std::mt19937 rng(5);
  const std::string labels = write_oblique_labels(*dir_, rng);
  const std::vector<float> decoded = f.all_vertices();
  std::uniform_int_distribution<std::uint64_t> vertex(0, f.meta().vertex_count - 1);
  std::uniform_real_distribution<float> radius(0.5f, 15), side(1, 30);
  auto a_point = [&] {
    const float* p = &decoded[3 * vertex(rng)];
    return std::array<float, 3>{p[0], p[1], p[2]};
  };
  auto region = [&](int kind) {
    const auto c = a_point();
    if (kind == 0) return sphere(c[0], c[1], c[2], radius(rng));
    if (kind == 1) {  // its surface through another point
      const auto q = a_point();
      const float r =
          std::sqrt((c[0] - q[0]) * (c[0] - q[0]) + (c[1] - q[1]) * (c[1] - q[1]) + (c[2] - q[2]) * (c[2] - q[2]));
      return sphere(c[0], c[1], c[2], std::min(r, 20.0f));
    }
    if (kind == 2) {  // a corner on a point
      char text[200];
      std::snprintf(text, sizeof text, "box:%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", c[0], c[1], c[2], c[0] + side(rng),
                    c[1] + side(rng), c[2] + side(rng));
      return parse_region(text);
    }
    return parse_region(labels + ":1");
  };
  int nonempty = 0;
  for (int trial = 0; trial < 60; ++trial) {
    SelectionCriteria c;
    c.include.push_back(region(trial % 4));
    if (trial % 3 == 1) c.include.push_back(region((trial + 1) % 3));
    if (trial % 4 == 2) c.exclude.push_back(region(trial % 3));
    if (trial % 5 == 3) c.ends_in.push_back(region(trial % 2));
    if (trial % 7 == 4) c.include.clear(), c.ends_in.push_back(region(0)), c.ends_in.push_back(region(1));
    const SelectionResult indexed = select_streamlines(f, c),
                          scan = select_streamlines(f, c, nullptr, SelectionPath::ScanTable);
    ASSERT_EQ(indexed.streamlines, scan.streamlines) << "trial " << trial;
    ASSERT_EQ(indexed.streamlines_per_region, scan.streamlines_per_region) << "trial " << trial;
    nonempty += !indexed.streamlines.empty();
  }
  EXPECT_GT(nonempty, 30);
}

// The window keeps each voxel's voxlines boxed between selections (VoxlineBoxes): a sphere dragged in steps, with a
// second region of every kind, ends and exclusions, selects what a selection without the boxes selects, whether the
// boxes are all kept or a budget of a third of that keeps some voxels out and lets unused ones go.
TEST_F(Selection, VoxlineBoxesKeptBetweenSelectionsChangeNothing) {
  const VxlFile f = VxlFile::open(dir_->file("packed_4mm.vxl"));
  std::mt19937 rng(9);
  const std::string labels = write_oblique_labels(*dir_, rng);
  const std::optional<VoxelVoxlines> index = VoxelVoxlines::of_file(f);
  ASSERT_TRUE(index.has_value());
  std::uniform_real_distribution<float> step(-3, 3), radius(2, 14);
  std::uint64_t all_kept_bytes = 0;
  for (const bool all : {true, false}) {
    const std::uint64_t budget = all ? VoxlineBoxes::kDefaultBudgetBytes : all_kept_bytes / 3;
    VoxlineBoxes boxes(f, budget);
    std::array<float, 3> centre = {float(kSynthCentre[0]), float(kSynthCentre[1]), float(kSynthCentre[2])};
    std::uint64_t kept = 0, cases = 0, first_boxed_bytes = 0;
    for (int trial = 0; trial < 48; ++trial) {
      for (float& c : centre) c += step(rng);
      SelectionCriteria c;
      const Region dragged = sphere(centre[0], centre[1], centre[2], radius(rng));
      (trial % 6 == 5 ? c.exclude : c.include).push_back(dragged);
      if (trial % 4 == 1) c.include.push_back(sphere(centre[0] + 15, centre[1], centre[2], 8));
      if (trial % 4 == 2) c.ends_in.push_back(parse_region("box:-80,-110,-60,0,80,80"));
      if (trial % 4 == 3) c.include.push_back(parse_region(labels + ":2"));
      if (trial % 6 == 5) c.include.push_back(sphere(centre[0], centre[1], centre[2], 30));
      const SelectionResult plain = select_streamlines(f, c, &*index),
                            boxed = select_streamlines(f, c, &*index, SelectionPath::Fastest, &boxes);
      ASSERT_EQ(boxed.streamlines, plain.streamlines) << "trial " << trial << " budget " << budget;
      ASSERT_EQ(boxed.streamlines_per_region, plain.streamlines_per_region) << "trial " << trial;
      EXPECT_LE(boxed.points_tested, plain.points_tested) << "trial " << trial;
      EXPECT_LE(boxes.bytes(), budget) << "trial " << trial;
      if (trial == 0) first_boxed_bytes = boxes.bytes();
      kept += boxed.streamlines.size();
      ++cases;
    }
    EXPECT_GT(kept, 20 * cases) << "the regions select something to compare";
    EXPECT_EQ(first_boxed_bytes, 0u) << "the first selection reads its voxels without boxing them";
    if (all) all_kept_bytes = boxes.bytes();
    EXPECT_GT(boxes.bytes(), 0u) << "some voxels boxed";
  }
}

TEST_F(Selection, ExcludeOnlyEndsOnlyAndLengthOnlyMatchTheReference) {
  const VxlFile f = VxlFile::open(dir_->file("f32.vxl"));
  std::vector<SelectionCriteria> all(4);
  all[0].exclude.push_back(sphere(0, -18, 10, 20));
  all[1].ends_in.push_back(parse_region("box:-80,-110,-60,0,80,80"));  // one end in the right hemisphere
  all[2].min_length = 50, all[2].max_length = 100;
  all[3].ends_in.push_back(sphere(-40, -20, 40, 25)), all[3].ends_in.push_back(sphere(40, -20, 40, 25));
  for (std::size_t i = 0; i < all.size(); ++i) {
    const SelectionResult r = select_streamlines(f, all[i]);
    EXPECT_EQ(r.streamlines, brute_force(*source_, all[i])) << "case " << i;
    EXPECT_FALSE(r.streamlines.empty()) << "case " << i;
  }
}

// Length limits on a file with packed positions follow the source (SLEN holds the source points' lengths, within
// a few float32 roundings of tckedit's, which random limits do not meet), as does every walk of the points with
// float32 positions.
TEST_F(Selection, LengthLimitsOnAPackedFileAreTheSources) {
  Tractogram copy = *source_;
  convert_tractogram(std::move(copy), dir_->file("packed.vxl"), settings(PositionEncoding::Packed));
  const VxlFile packed = VxlFile::open(dir_->file("packed.vxl")), f32 = VxlFile::open(dir_->file("f32.vxl"));
  ASSERT_FALSE(packed.streamline_lengths().empty());
  EXPECT_TRUE(std::equal(packed.streamline_lengths().begin(), packed.streamline_lengths().end(),
                         f32.streamline_lengths().begin(), f32.streamline_lengths().end()));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> limit(20, 160);
  int cut = 0;
  for (int trial = 0; trial < 20; ++trial) {
    SelectionCriteria c;
    const double a = limit(rng), b = limit(rng);
    if (trial % 3 != 1) c.min_length = std::min(a, b);
    if (trial % 3 != 2) c.max_length = std::max(a, b);
    const SelectionResult r = select_streamlines(packed, c);
    ASSERT_EQ(r.streamlines, brute_force(*source_, c)) << "trial " << trial;
    EXPECT_EQ(r.streamlines_measured, 0u) << "a packed file's lengths are SLEN's";
    EXPECT_EQ(r.bytes_read, packed.voxels().size_bytes() + 4 * r.lengths_read) << "lengths only";
    ASSERT_EQ(select_streamlines(f32, c, nullptr, SelectionPath::ScanTable).streamlines, r.streamlines);
    cut += !r.streamlines.empty() && r.streamlines.size() < source_->streamline_count();
  }
  EXPECT_GT(cut, 10);
}

TEST_F(Selection, RegionsOutsideEverythingOrHoldingEverything) {
  const VxlFile f = VxlFile::open(dir_->file("f32.vxl"));
  SelectionCriteria outside;
  outside.include.push_back(sphere(1000, 1000, 1000, 50));
  const SelectionResult none = select_streamlines(f, outside);
  EXPECT_TRUE(none.streamlines.empty());
  EXPECT_EQ(none.voxels_touched, 0u);  // no voxel read at all
  EXPECT_EQ(none.points_tested, 0u);
  SelectionCriteria everything;
  everything.include.push_back(parse_region("box:-1000,-1000,-1000,1000,1000,1000"));
  const SelectionResult all = select_streamlines(f, everything);
  EXPECT_EQ(all.streamlines.size(), source_->streamline_count());
  EXPECT_EQ(all.points_tested, 0u);  // a region holding a voxel's whole box needs none of its points
  outside.invert = true;
  EXPECT_EQ(select_streamlines(f, outside).streamlines.size(), source_->streamline_count());
}

// A level of detail is applied last, after the regions, the lengths and --invert: of what they keep, the streamlines
// of depth >= level (spec §6.5), about an eighth a level; a level the file has not is refused.
TEST_F(Selection, ALevelKeepsTheStreamlinesOfThatDepthAmongThoseTheCriteriaKeep) {
  const VxlFile file = VxlFile::open(dir_->file("packed_4mm.vxl"));
  const std::uint32_t levels = file.level_count();
  ASSERT_EQ(levels, kDefaultLevels);
  auto at_level = [&](std::vector<std::uint64_t> kept, std::uint32_t level) {
    std::erase_if(kept, [&](std::uint64_t s) { return streamline_depth(s, levels) < level; });
    return kept;
  };
  SelectionCriteria in_sphere;
  in_sphere.include.push_back(sphere(0, -18, 10, 30));
  SelectionCriteria inverted = in_sphere;
  inverted.invert = true;
  SelectionCriteria lengths;
  lengths.min_length = 40;
  for (const SelectionCriteria& base : {SelectionCriteria{}, in_sphere, inverted, lengths}) {
    const std::vector<std::uint64_t> all = select_streamlines(file, base).streamlines;
    for (std::uint32_t level = 0; level < levels; ++level) {
      SelectionCriteria c = base;
      c.level = level;
      const std::vector<std::uint64_t> kept = select_streamlines(file, c).streamlines;
      EXPECT_EQ(kept, at_level(all, level)) << "level " << level;
      if (level == 1 && base.include.empty() && !base.min_length) {  // about an eighth of 3000
        EXPECT_GT(kept.size(), all.size() / 8 - 120);
        EXPECT_LT(kept.size(), all.size() / 8 + 120);
      }
    }
  }
  SelectionCriteria beyond;
  beyond.level = levels;
  const Error error = test::hostile::error_of([&] { select_streamlines(file, beyond); });
  EXPECT_EQ(error.kind(), ErrorKind::Usage);
  EXPECT_NE(std::string(error.what()).find("has 5 levels of detail: 0 to 4"), std::string::npos) << error.what();
}

// With a level's own voxlines (LevelVoxlines, as a viewer drawing that level holds them), only they are searched:
// the same streamlines as through the whole index, each region's count that of the level's streamlines alone, and
// far fewer points tested. Voxlines of another level are refused.
TEST_F(Selection, ALevelsOwnVoxlinesSelectWhatTheWholeIndexSelectsAtThatLevel) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint64_t> point(0, source_->point_count() - 1);
  std::uniform_real_distribution<float> radius(5, 40);
  auto near_a_point = [&] {
    const float* p = &source_->positions[3 * point(rng)];
    return sphere(p[0], p[1], p[2], radius(rng));
  };
  for (const char* file : {"f32.vxl", "packed_4mm.vxl"}) {
    const VxlFile f = VxlFile::open(dir_->file(file));
    const std::uint32_t levels = f.level_count();
    ASSERT_EQ(levels, kDefaultLevels);
    std::uint64_t tested_whole = 0, tested_level = 0;
    for (std::uint32_t level = 1; level < levels; ++level) {
      const LevelVoxlines lists(f, level);
      for (int trial = 0; trial < 12; ++trial) {
        SelectionCriteria c;
        c.include.push_back(near_a_point());
        if (trial % 3 == 1) c.exclude.push_back(near_a_point());
        if (trial % 4 == 2) c.ends_in.push_back(near_a_point());
        if (trial % 5 == 3) c.min_length = 50;
        c.invert = trial % 6 == 4;
        c.level = level;
        const SelectionResult whole = select_streamlines(f, c),
                              own = select_streamlines(f, c, nullptr, SelectionPath::Fastest, nullptr, &lists);
        ASSERT_EQ(own.streamlines, whole.streamlines) << file << " level " << level << " trial " << trial;
        std::vector<Region> in_order = c.include;  // the counts' order: includes, ends-in, excludes
        in_order.insert(in_order.end(), c.ends_in.begin(), c.ends_in.end());
        in_order.insert(in_order.end(), c.exclude.begin(), c.exclude.end());
        ASSERT_EQ(own.streamlines_per_region.size(), in_order.size());
        for (std::size_t r = 0; r < in_order.size(); ++r) {
          SelectionCriteria alone;
          (r >= c.include.size() && r < c.include.size() + c.ends_in.size() ? alone.ends_in : alone.include)
              .push_back(in_order[r]);
          alone.level = level;
          EXPECT_EQ(own.streamlines_per_region[r], select_streamlines(f, alone).streamlines.size())
              << file << " level " << level << " trial " << trial << " region " << r;
        }
        tested_whole += whole.points_tested, tested_level += own.points_tested;
      }
    }
    EXPECT_LT(tested_level * 4, tested_whole) << file << ": the level's voxlines alone are tested";
    SelectionCriteria other;
    other.include.push_back(sphere(0, 0, 0, 20));
    other.level = 1;
    const LevelVoxlines level_two(f, 2);
    EXPECT_THROW(select_streamlines(f, other, nullptr, SelectionPath::Fastest, nullptr, &level_two), std::logic_error);
  }
}

// A streamline without points is never selected, as tckedit never writes one: not by an exclude, an inverted
// query or a length limit of 0, which every streamline with points passes.
TEST(SelectionEmptyStreamlines, AreNeverSelected) {
  ScratchDir dir;
  Tractogram t;
  const float line[] = {0, 0, 0, 10, 0, 0, 20, 0, 0};
  for (int s = 0; s < 6; ++s) {
    if (s % 2 == 0) t.add_streamline(line, 0);
    t.add_streamline(line, s == 5 ? 1 : 3);  // the last one a single point
  }
  convert_tractogram(std::move(t), dir.file("e.vxl"), settings(PositionEncoding::Float32));
  const VxlFile f = VxlFile::open(dir.file("e.vxl"));
  ASSERT_EQ(f.meta().streamline_count, 9u);
  const std::vector<std::uint64_t> with_points = {1, 2, 4, 5, 7, 8};
  SelectionCriteria exclude;
  exclude.exclude.push_back(parse_region("500,500,500,1"));
  EXPECT_EQ(select_streamlines(f, exclude).streamlines, with_points);
  SelectionCriteria inverted;
  inverted.include.push_back(parse_region("500,500,500,1"));
  inverted.invert = true;
  EXPECT_EQ(select_streamlines(f, inverted).streamlines, with_points);
  SelectionCriteria length;
  length.min_length = 0;
  EXPECT_EQ(select_streamlines(f, length).streamlines, with_points);
}

// Two fixed-step streamlines (point k = p0 + k·v in float32) whose float32 lengths, as tckedit sums them, lie
// just beyond a limit that their double-precision lengths (SLEN's) meet: tckedit 3.0.3 drops both, given that
// SLEN length as -maxlength and -minlength. The first ends 54.020523 long against SLEN's 54.020515, the second
// 66.506897 against 66.50692.
TEST(SelectionLengths, FixedStepStreamlinesOnALimitAreDecidedAsTckeditDecides) {
  ScratchDir dir;
  Tractogram t;
  auto add = [&t](std::array<float, 3> p0, std::array<float, 3> v, int n) {
    std::vector<float> xyz;
    for (int k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) xyz.push_back(p0[c] + float(k) * v[c]);
    t.add_streamline(xyz.data(), n);
  };
  add({-33.150001525878906f, -21.059999465942383f, 24.100000381469727f},
      {-0.375f, -0.29899999499320984f, -0.1420000046491623f}, 109);
  add({-23.420000076293945f, 10.40999984741211f, -16.149999618530273f},
      {-0.4480000138282776f, 0.16200000047683716f, -0.15199999511241913f}, 134);
  convert_tractogram(std::move(t), dir.file("steps.vxl"), settings(PositionEncoding::Float32));
  const VxlFile f = VxlFile::open(dir.file("steps.vxl"));
  ASSERT_EQ(f.streamline_lengths()[0], 54.02051544189453f);
  ASSERT_EQ(f.streamline_lengths()[1], 66.50691986083984f);
  for (const SelectionPath path : {SelectionPath::Fastest, SelectionPath::ScanTable}) {
    SelectionCriteria at_most, at_least, at_most_float, at_least_float;
    at_most.max_length = 54.02051544189453;  // streamline 1 is 66.5 mm long
    at_least.min_length = 66.50691986083984;
    at_most_float.max_length = 54.02052307128906;
    at_least_float.min_length = 66.50689697265625;
    EXPECT_EQ(select_streamlines(f, at_most, nullptr, path).streamlines, std::vector<std::uint64_t>{});
    EXPECT_EQ(select_streamlines(f, at_least, nullptr, path).streamlines, std::vector<std::uint64_t>{});
    EXPECT_EQ(select_streamlines(f, at_most_float, nullptr, path).streamlines, std::vector<std::uint64_t>{0});
    EXPECT_EQ(select_streamlines(f, at_least_float, nullptr, path).streamlines, std::vector<std::uint64_t>{1});
  }
  SelectionCriteria far;
  far.min_length = 20, far.max_length = 100;
  const SelectionResult r = select_streamlines(f, far);
  EXPECT_EQ(r.lengths_read, 2u);
  EXPECT_EQ(r.streamlines_measured, 0u) << "SLEN decides lengths far from the limits";
}

// The source header's step_size widens the limits as tckedit reads it (a tenth of a step, or half a step over
// downsample_factor; a value that does not read as one number is no step_size; a negative one narrows; a
// downsample_factor of 0 opens them; 0 over 0 closes them, even without a length option; an unreadable
// downsample_factor is refused). Four straight streamlines 9.94, 9.96, 10.04 and 10.06 mm long, --min-length 10.
TEST(SelectionLengths, TheSourceStepSizeWidensTheLimitsAsTckeditReadsIt) {
  ScratchDir dir;
  struct Case {
    std::vector<std::pair<std::string, std::vector<std::string>>> header;
    std::size_t kept, kept_without_limits;
  };
  const std::vector<Case> cases = {
      {{}, 2, 4},
      {{{"step_size", {"0.5"}}}, 3, 4},
      {{{"step_size", {"0.5 # mm"}}}, 3, 4},
      {{{"step_size", {"0.5 mm"}}}, 2, 4},
      {{{"step_size", {"0.5", "0.5"}}}, 2, 4},
      {{{"step_size", {"-0.5"}}}, 1, 4},
      {{{"step_size", {"inf"}}}, 2, 4},
      {{{"step_size", {"1e39"}}}, 2, 4},
      {{{"step_size", {"0.5"}}, {"downsample_factor", {"2.5"}}}, 4, 4},
      {{{"step_size", {"0.5"}}, {"downsample_factor", {"0"}}}, 4, 4},
      {{{"step_size", {"0"}}, {"downsample_factor", {"0"}}}, 0, 0},
      {{{"step_size", {"-200"}}}, 0, 0},
  };
  auto file_with = [&](const auto& header, const std::string& name) {
    Tractogram t;
    for (const float x : {9.94f, 9.96f, 10.04f, 10.06f}) {
      const float line[] = {0, 0, 0, x, 0, 0};
      t.add_streamline(line, 2);
    }
    for (const auto& [key, lines] : header) t.source.header[key] = lines;
    convert_tractogram(std::move(t), dir.file(name), settings(PositionEncoding::Float32));
    return VxlFile::open(dir.file(name));
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const VxlFile f = file_with(cases[i].header, std::to_string(i) + ".vxl");
    SelectionCriteria limit, none;
    limit.min_length = 10;
    EXPECT_EQ(select_streamlines(f, limit).streamlines.size(), cases[i].kept) << "case " << i;
    EXPECT_EQ(select_streamlines(f, none).streamlines.size(), cases[i].kept_without_limits) << "case " << i;
  }
  const VxlFile refused =
      file_with(std::vector<std::pair<std::string, std::vector<std::string>>>{{"step_size", {"0.5"}},
                                                                              {"downsample_factor", {"two"}}},
                "refused.vxl");
  try {
    (void)select_streamlines(refused, SelectionCriteria{});
    ADD_FAILURE() << "an unreadable downsample_factor was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Input);
    EXPECT_NE(std::string(e.what()).find("downsample_factor 'two'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("refused.vxl"), std::string::npos) << e.what();
  }
  EXPECT_EQ(mrtrix_float(" 0.25\t"), 0.25f);
  EXPECT_EQ(mrtrix_float("-INF"), -std::numeric_limits<float>::infinity());
  EXPECT_FALSE(mrtrix_float("0x10").has_value());
  EXPECT_FALSE(mrtrix_float("").has_value());
}

TEST_F(Selection, ASmallSphereTestsOnlyTheVoxelsItTouches) {
  const VxlFile f = VxlFile::open(dir_->file("f32.vxl"));
  SelectionCriteria c;
  const float* p = &source_->positions[3 * (source_->offsets[0] + 10)];  // a point of streamline 0
  c.include.push_back(sphere(p[0], p[1], p[2], 5));
  const SelectionResult r = select_streamlines(f, c);
  // A 10 mm ball meets at most 2 x 2 x 2 voxel cubes of 10 mm; their tight bounds reach a step beyond the
  // cube (the connecting vertices), so some neighbours may be looked at too, never more than 3 x 3 x 3.
  EXPECT_LE(r.voxels_touched, 27u);
  EXPECT_LT(r.points_tested, f.meta().point_count / 10);
  ASSERT_FALSE(r.streamlines.empty());
  EXPECT_EQ(r.streamlines[0], 0u);
}

// The per-voxel index is VXLN inverted: every voxline once, under its own voxel, in streamline order; with packed
// positions and levels of detail (a cursor per depth) it selects what the scan of the whole table selects.
TEST(SelectionIndex, ListsEveryVoxlineOnceAndSelectsWhatTheScanSelects) {
  ScratchDir dir;
  ConvertSettings packed = settings(PositionEncoding::Packed, 4.0);
  packed.levels = 4;
  convert_tractogram(synth(3000, 5), dir.file("p.vxl"), packed);
  const VxlFile f = VxlFile::open(dir.file("p.vxl"));
  ASSERT_GT(f.level_count(), 1u);
  const std::optional<VoxelVoxlines> index = VoxelVoxlines::build(f);
  ASSERT_TRUE(index.has_value());
  // The expected lists, from a walk of VXLN in streamline order (spec §5.6, §5.7, §6.5).
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> expected(f.voxels().size());
  const auto strm = f.streamline_first_voxline();
  for (std::uint64_t s = 0; s + 1 < strm.size(); ++s)
    for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) {
      const VoxlineEntry& e = f.voxlines()[j];
      std::uint32_t flags = 0;
      if (e.count_flags & kVoxlineSyntheticFirst) flags |= IndexedVoxline::kSyntheticFirst;
      if (j == strm[s]) flags |= IndexedVoxline::kFirstOfStreamline;
      if (j + 1 == strm[s + 1]) flags |= IndexedVoxline::kLastOfStreamline;
      expected[e.voxel].emplace_back(std::uint32_t(s), flags);
    }
  for (std::size_t v = 0; v < f.voxels().size(); ++v) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> listed;
    for (const IndexedVoxline& e : index->of_voxel(v))
      listed.emplace_back(e.streamline(), e.word & ~IndexedVoxline::kStreamlineMask);
    ASSERT_EQ(listed, expected[v]) << "voxel " << v;
  }

  std::mt19937 rng(3);
  std::uniform_int_distribution<std::size_t> voxel(0, f.voxels().size() - 1);
  std::uniform_real_distribution<float> radius(0, 20);
  int cut = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const VoxelEntry& v = f.voxels()[voxel(rng)];
    SelectionCriteria c;
    c.include.push_back(sphere(v.tight_min[0], v.tight_max[1], v.tight_min[2], radius(rng)));
    if (trial % 3 == 0) c.ends_in.push_back(sphere(v.tight_max[0], v.tight_min[1], v.tight_max[2], 15));
    if (trial % 4 == 1) c.exclude.push_back(sphere(v.tight_max[0], v.tight_max[1], v.tight_max[2], 6));
    const SelectionResult scan = select_streamlines(f, c, nullptr, SelectionPath::ScanTable),
                          indexed = select_streamlines(f, c, &*index), from_file = select_streamlines(f, c);
    ASSERT_EQ(from_file.streamlines, scan.streamlines) << "trial " << trial;
    ASSERT_EQ(indexed.streamlines, scan.streamlines) << "trial " << trial;
    ASSERT_EQ(indexed.streamlines_per_region, scan.streamlines_per_region) << "trial " << trial;
    cut += !scan.streamlines.empty() && scan.streamlines.size() < 3000;
  }
  EXPECT_GT(cut, 10);
  // A small sphere: the index reads the few touched voxels' lists, not the whole voxline table.
  const VoxelEntry& v = f.voxels()[f.voxels().size() / 2];
  SelectionCriteria small;
  small.include.push_back(sphere(v.tight_min[0] + 1, v.tight_min[1] + 1, v.tight_min[2] + 1, 2));
  const SelectionResult scan = select_streamlines(f, small, nullptr, SelectionPath::ScanTable),
                        indexed = select_streamlines(f, small, &*index);
  EXPECT_EQ(indexed.streamlines, scan.streamlines);
  const std::uint64_t always = f.voxels().size_bytes();  // both look at every voxel's bounds
  EXPECT_LT(indexed.bytes_read - always - indexed.points_tested * 4,
            (scan.bytes_read - always - scan.points_tested * 4) / 4);
}

// A streamed conversion fills the index a range of voxels at a time (fill_voxel_index through a bounded buffer):
// with buffers of one list entry up to the whole index, allocated or the caller's, the payload is the one filled in
// memory in one range. Where it holds every list it fills them as it writes VXLN, streamline by streamline
// (VoxelIndexLists): the same payload, and lists that the streamlines overflow or leave short are told apart.
TEST(SelectionIndex, FilledInPartsOrStreamlineByStreamlineItIsTheSameIndex) {
  ScratchDir dir;
  convert_tractogram(synth(3000, 5), dir.file("p.vxl"), settings(PositionEncoding::Packed, 4.0));
  const VxlFile f = VxlFile::open(dir.file("p.vxl"));
  const auto strm = f.streamline_first_voxline();
  const auto voxlines = f.voxlines();
  std::vector<std::uint8_t> whole(voxel_index_bytes(f.meta()));
  ASSERT_GT(whole.size(), 0u);
  fill_voxel_index_payload(whole, strm, voxlines);
  const auto* stored = reinterpret_cast<const std::uint8_t*>(f.voxel_index_first().data());
  EXPECT_TRUE(std::equal(whole.begin(), whole.end(), stored)) << "the file's VXIX is the one filled in memory";
  // Each buffer allocated, or given by the caller (its size then limits the range, not buffer_bytes).
  for (const std::uint64_t buffer : {std::uint64_t(4), std::uint64_t(4096), std::uint64_t(1) << 16}) {
    for (const bool given : {false, true}) {
      SCOPED_TRACE(testing::Message() << buffer << (given ? " bytes given" : " bytes allocated"));
      std::vector<std::uint8_t> parts;
      int writes = 0;
      std::vector<IndexedVoxline> caller_memory(buffer / sizeof(IndexedVoxline));
      VoxelIndexIo io;
      if (given) io.buffer = caller_memory;
      io.read_voxlines = [&](std::uint64_t first, std::span<VoxlineEntry> out) {
        std::copy_n(voxlines.begin() + static_cast<std::ptrdiff_t>(first), out.size(), out.begin());
      };
      io.read_streamline_table = [&](std::uint64_t first, std::span<std::uint64_t> out) {
        std::copy_n(strm.begin() + static_cast<std::ptrdiff_t>(first), out.size(), out.begin());
      };
      io.write = [&](std::span<const std::uint8_t> bytes) {
        parts.insert(parts.end(), bytes.begin(), bytes.end());
        ++writes;
      };
      fill_voxel_index(f.voxels().size(), voxlines.size(), strm.size() - 1, io, given ? ~std::uint64_t(0) : buffer);
      EXPECT_EQ(parts, whole);
      if (buffer == 4) {
        EXPECT_EQ(writes, 1 + static_cast<int>(f.voxels().size())) << "one range per voxel";
      }
      if (buffer == 4096) {
        EXPECT_GT(writes, 2) << "more than one range";
      }
    }
  }
  std::vector<std::uint64_t> counts(f.voxels().size());
  for (std::size_t v = 0; v < counts.size(); ++v) counts[v] = f.voxels()[v].vertex_count - f.voxels()[v].segment_count;
  VoxelIndexLists lists(counts);
  for (std::uint64_t s = 0; s + 1 < strm.size(); ++s) {
    EXPECT_FALSE(lists.complete()) << "before streamline " << s;
    ASSERT_TRUE(lists.add_streamline(s, voxlines.subspan(strm[s], strm[s + 1] - strm[s])));
  }
  EXPECT_TRUE(lists.complete());
  std::vector<std::uint8_t> filled;
  for (const auto part : {std::as_bytes(lists.starts()), std::as_bytes(lists.lists())})
    for (const std::byte b : part) filled.push_back(static_cast<std::uint8_t>(b));
  ASSERT_EQ(filled.size(), voxel_index_bytes(f.meta()));
  EXPECT_EQ(filled, whole) << "streamline by streamline";
  // One voxline more than a voxel's count overflows its list; a voxel out of range is refused.
  std::vector<std::uint64_t> fewer = counts;
  const std::size_t v = voxlines[0].voxel;
  fewer[v] = 0;
  VoxelIndexLists short_lists(fewer);
  EXPECT_FALSE(short_lists.add_streamline(0, voxlines.first(1)));
  VoxelIndexLists again(counts);
  VoxlineEntry outside = voxlines[0];
  outside.voxel = static_cast<std::uint32_t>(counts.size());
  EXPECT_FALSE(again.add_streamline(0, {&outside, 1}));
}

// Voxline and streamline tables that do not hold together, checksums resealed so that only the structure
// can tell: building the index, and selecting with or without it, is refused naming the file (Input) —
// never a read past a table. An index holds no point counts (the block says where a voxline ends), so a count
// that lies leaves the lists right: selecting through them gives the undamaged file's answer.
TEST(SelectionIndex, TablesThatDoNotHoldTogetherAreRefused) {
  ScratchDir dir;
  const test::VxlBytes valid = test::VxlBytes::make(dir.file("h.vxl"));
  const std::uint64_t vxln = valid.offset_of("VXLN"), strm = valid.offset_of("STRM");
  struct Damage {
    const char* name;
    std::uint64_t at;
    std::uint32_t value;
    bool in_the_index;  // whether the lists built from the damaged tables differ
  };
  const Damage cases[] = {{"voxel past the table", vxln + 8 * 3, 1u << 30, true},
                          {"voxline with no points", vxln + 8 * 3 + 4, 0, true},
                          {"more points than the block holds", vxln + 8 * 3 + 4, 1u << 20, false},
                          {"streamline table decreasing", strm + 8 * 5, 0, true},
                          {"streamline table past the voxlines", strm + 8 * 40, 1u << 30, true}};
  SelectionCriteria everywhere;
  everywhere.include.push_back(parse_region("box:-1000,-1000,-1000,1000,1000,1000"));
  const std::vector<std::uint64_t> undamaged =
      select_streamlines(VxlFile::open(dir.file("h.vxl")), everywhere).streamlines;
  for (const Damage& d : cases) {
    SCOPED_TRACE(d.name);
    test::VxlBytes b = valid;
    std::memcpy(b.bytes.data() + d.at, &d.value, 4);
    b.reseal();
    b.write(dir.file("bad.vxl"));
    const VxlFile f = VxlFile::open(dir.file("bad.vxl"));
    auto refused = [&](const auto& run) {
      try {
        run();
      } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Input) << e.what();
        EXPECT_NE(std::string(e.what()).find("bad.vxl"), std::string::npos) << e.what();
        return true;
      }
      return false;
    };
    EXPECT_TRUE(refused([&] { select_streamlines(f, everywhere, nullptr, SelectionPath::ScanTable); }));
    std::optional<VoxelVoxlines> index;
    if (!refused([&] { index = VoxelVoxlines::build(f); })) {
      ASSERT_TRUE(index.has_value());
      if (d.in_the_index)
        EXPECT_TRUE(refused([&] { select_streamlines(f, everywhere, &*index); }));
      else
        EXPECT_EQ(select_streamlines(f, everywhere, &*index).streamlines, undamaged);
    }
  }
}

TEST(SelectionRegions, ASphereHoldsItsSurfaceAsTckeditDoes) {
  const Region r = parse_region("0,0,0,5");
  const float on[3] = {3, 4, 0}, beyond[3] = {3, 4, 0.001f}, centre[3] = {0, 0, 0};
  EXPECT_TRUE(r.contains(on));
  EXPECT_FALSE(r.contains(beyond));
  EXPECT_TRUE(r.contains(centre));
  const Region zero = parse_region("1.5,2.5,-3.25,0");
  const float at[3] = {1.5f, 2.5f, -3.25f}, next[3] = {1.5f, 2.5f, std::nextafter(-3.25f, 0.0f)};
  EXPECT_TRUE(zero.contains(at));
  EXPECT_FALSE(zero.contains(next));
  // Where the order of the float32 sum decides: tckedit (Eigen) sums x² + (y² + z²). Each radius squared is one
  // of the two orders' sums for its point, as tckedit 3.0.3 was seen to keep the first point and drop the second.
  const Region kept_tie = parse_region("0,0,0,5.795355796813965");
  const float kept_point[3] = {4.376504421234131f, -1.4132816791534424f, -3.5263283252716064f};
  EXPECT_TRUE(kept_tie.contains(kept_point)) << "summed (x² + y²) + z²";
  const Region dropped_tie = parse_region("0,0,0,6.2973432540893555");
  const float dropped_point[3] = {3.0867607593536377f, 4.184473991394043f, -3.552269697189331f};
  EXPECT_FALSE(dropped_tie.contains(dropped_point)) << "summed (x² + y²) + z²";
  const Region box = parse_region("box:0,0,0,1,2,3");
  const float corner[3] = {1, 2, 3}, out[3] = {1, 2, 3.0001f};
  EXPECT_TRUE(box.contains(corner));
  EXPECT_FALSE(box.contains(out));
}

// Numbers are read as tckedit reads them: a decimal to a double, then to a float. 1 + 2^-24 + 2^-80 rounds to
// the double 1 + 2^-24, a tie between the floats 1 and 1 + 2^-23 that goes to 1 (the even one); read straight
// to a float it would be 1 + 2^-23. A radius below the floats' least (1e-46) is 0, as there; one beyond their
// range is refused naming the radius; "+-5" is no number.
TEST(SelectionRegions, NumbersAreReadAsTckeditReadsThem) {
  const Region tie =
      parse_region("0,0,0,1.00000005960464477539062582718061255302767487140869206996285356581211090087890625");
  const float one[3] = {1, 0, 0}, above[3] = {std::nextafter(1.0f, 2.0f), 0, 0};
  EXPECT_TRUE(tie.contains(one));
  EXPECT_FALSE(tie.contains(above)) << "the radius was read straight to a float";
  const Region tiny = parse_region("1,2,3,1e-46");
  const float centre[3] = {1, 2, 3}, next[3] = {1, 2, std::nextafter(3.0f, 4.0f)};
  EXPECT_TRUE(tiny.contains(centre));
  EXPECT_FALSE(tiny.contains(next));
  for (const char* refused : {"+-5,0,0,1", "0,++1,0,1", "0,0,0,1e308"}) {
    try {
      (void)parse_region(refused);
      ADD_FAILURE() << refused << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Usage) << refused;
      if (std::string(refused).ends_with("1e308")) {
        EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
      }
    }
  }
}

// A mask's lookup is tckedit's float32 affine product (Eigen's Transform<float, 3, AffineCompact> times the
// point), whose rounding depends on the order of the sums: the lookup sums as Eigen does, to the bit, on
// oblique matrices and points spread over a brain's range. Summed left to right, about a quarter would differ.
TEST(SelectionRegions, MaskLookupRoundsAsEigensAffineProduct) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> coordinate(-120.0f, 120.0f), coefficient(-1.0f, 1.0f);
  int differ = 0;
  for (int n = 0; n < 100000; ++n) {
    Eigen::Transform<float, 3, Eigen::AffineCompact> t;
    float rows[12];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c)
        rows[4 * r + c] = t.matrix()(r, c) = c == 3 ? coordinate(random) : coefficient(random);
    const float p[3] = {coordinate(random), coordinate(random), coordinate(random)};
    const Eigen::Vector3f v = t * Eigen::Vector3f(p[0], p[1], p[2]);
    for (int r = 0; r < 3; ++r) differ += mask_row(rows + 4 * r, p) != v[r];
  }
  EXPECT_EQ(differ, 0);
}

// A mask's header read as MRtrix reads it (converter/readers/image_geometry.h), each case with a point that a
// reading otherwise would put in another voxel. A 4^3 mask of 2 mm voxels whose centres lie at -3, -1, 1, 3 mm on
// every axis (with its sform); only voxel (1, 1, 1), centred at (-1, -1, -1), is set.
TEST(SelectionRegions, MaskHeadersAreReadAsMRtrixReadsThem) {
  ScratchDir dir;
  std::vector<std::int16_t> one(64, 0);
  one[(1 * 4 + 1) * 4 + 1] = 1;
  const std::array<double, 12> grid = {2, 0, 0, -3, 0, 2, 0, -3, 0, 0, 2, -3};
  const float centre[3] = {-1, -1, -1};
  // Rewrites the mask's header through nifti_clib.
  auto rewrite = [&](const std::string& name, auto&& change) {
    const std::string path = dir.file(name);
    test::write_nifti_int16(path, {4, 4, 4}, one, grid);
    nifti_image* nim = nifti_image_read(path.c_str(), 1);
    change(*nim);
    nifti_image_write(nim);
    nifti_image_free(nim);
    return path;
  };
  // Units of metres (or microns) are ignored, as MRtrix ignores them (not scaled by 1000).
  EXPECT_TRUE(
      parse_region(rewrite("metres.nii", [](nifti_image& n) { n.xyz_units = NIFTI_UNITS_METER; })).contains(centre));
  // Neither sform nor qform: the image centred on the origin, as MRtrix places it (not voxel 0 at the origin).
  EXPECT_TRUE(
      parse_region(rewrite("none.nii", [](nifti_image& n) { n.sform_code = n.qform_code = 0; })).contains(centre));
  // The same for an MRtrix image without 'transform:'.
  test::MifSpec mif;
  mif.dims = {4, 4, 4};
  mif.vox = {2, 2, 2};
  mif.layout = {1, 2, 3};
  std::string bytes = test::mif_bytes(mif, std::vector<double>(one.begin(), one.end()));
  for (std::size_t at; (at = bytes.find("transform:")) != std::string::npos;) bytes.replace(at, 10, "comments: ");
  test::write_file(dir.file("none.mif"), std::vector<char>(bytes.begin(), bytes.end()));
  EXPECT_TRUE(parse_region(dir.file("none.mif")).contains(centre));
  // pixdim within a relative 1e-5 of the sform's axis lengths: MRtrix keeps pixdim as the voxel size.
  const std::string near = rewrite("pixdim.nii", [](nifti_image& n) {
    n.pixdim[1] = n.dx = 2.0f * (1 + 6e-6f);
    n.pixdim[2] = n.dy = n.pixdim[3] = n.dz = 2.0f;
  });
  EXPECT_EQ(read_volume_image(near).voxel_to_ras[0], double(2.0f * (1 + 6e-6f)));
  // Stored right to left (LAS): x flipped, voxel i centred at 3 - 2i. A point on the face between voxels 1 and
  // 2 (x = 0) is in voxel 1 (x = 1) in MRtrix's realigned image, where it rounds from the other side; in the
  // stored order it rounded to voxel 2.
  std::vector<std::int16_t> left(64, 0);
  left[(1 * 4 + 1) * 4 + 1] = 1;
  test::write_nifti_int16(dir.file("las.nii"), {4, 4, 4}, left, {-2, 0, 0, 3, 0, 2, 0, -3, 0, 0, 2, -3});
  const float face[3] = {0, -1, -1};
  EXPECT_TRUE(parse_region(dir.file("las.nii")).contains(face));
}

TEST(SelectionRegions, AMaskHoldsThePointsWhoseNearestVoxelIsSet) {
  ScratchDir dir;
  // 4 x 4 x 4 voxels of 2 mm, voxel (i, j, k) centred at (10 + 2i, -2j, 2k) (y flipped); voxel (1, 2, 3) = 7.
  std::vector<std::int16_t> v(64, 0);
  v[(3 * 4 + 2) * 4 + 1] = 7;
  test::write_nifti_int16(dir.file("m.nii"), {4, 4, 4}, v, {2, 0, 0, 10, 0, -2, 0, 0, 0, 0, 2, 0});
  const Region mask = parse_region(dir.file("m.nii"));
  const Region label = parse_region(dir.file("m.nii") + ":7");
  const float centre[3] = {12, -4, 6}, inside_edge[3] = {12.99f, -4.99f, 6.99f}, outside[3] = {13.01f, -4, 6};
  const float far[3] = {100, 0, 0};
  for (const Region* r : {&mask, &label}) {
    EXPECT_TRUE(r->contains(centre));
    EXPECT_TRUE(r->contains(inside_edge));
    EXPECT_FALSE(r->contains(outside));
    EXPECT_FALSE(r->contains(far));
  }
  try {
    parse_region(dir.file("m.nii") + ":3");
    ADD_FAILURE() << "an absent label was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("label 3"), std::string::npos) << e.what();
  }
}

TEST(SelectionOutputs, EveryFormatHoldsTheSelectedStreamlinesInSourceOrder) {
  ScratchDir dir;
  Tractogram t = synth(400, 3);
  // Values and groups, to see them follow the selection.
  ValueSet per_point{"fa", {}}, per_streamline{"weight", {}};
  for (std::uint64_t i = 0; i < t.point_count(); ++i) per_point.values.push_back(float(i));
  for (std::uint64_t s = 0; s < t.streamline_count(); ++s) per_streamline.values.push_back(float(s) / 2);
  t.point_values.push_back(per_point);
  t.streamline_values.push_back(per_streamline);
  StreamlineGroup odd{"odd", {}};
  for (std::uint64_t s = 1; s < t.streamline_count(); s += 2) odd.members.push_back(s);
  t.groups.push_back(odd);
  const Tractogram source = t;
  convert_tractogram(std::move(t), dir.file("in.vxl"), settings(PositionEncoding::Float32));
  const VxlFile f = VxlFile::open(dir.file("in.vxl"));
  SelectionCriteria c;
  c.include.push_back(parse_region("0,-18,10,15"));
  const std::vector<std::uint64_t> kept = select_streamlines(f, c).streamlines;
  ASSERT_GT(kept.size(), 5u);
  ASSERT_LT(kept.size(), source.streamline_count());
  const StreamlineSubset subset(source.streamline_count(), kept);
  for (const char* name : {"out.tck", "out.trx", "out.vtk", "out.vxl"}) {
    const std::string out = dir.file(name);
    write_selection(f, subset, out, {}, {});
    if (std::string(name) == "out.vxl") {
      ASSERT_TRUE(verify_vxl(out).valid) << verify_vxl(out).problem;
    }
    Tractogram back = std::string(name) == "out.vxl" ? Tractogram{} : read_tractogram(out);
    if (std::string(name) == "out.vxl") {
      write_selection(VxlFile::open(out),
                      StreamlineSubset(kept.size(),
                                       [&] {
                                         std::vector<std::uint64_t> all(kept.size());
                                         for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
                                         return all;
                                       }()),
                      dir.file("back.trx"), {}, {});
      back = read_tractogram(dir.file("back.trx"));
    }
    ASSERT_EQ(back.streamline_count(), kept.size()) << name;
    for (std::size_t i = 0; i < kept.size(); ++i) {
      const std::uint64_t s = kept[i];
      const std::uint64_t n = source.offsets[s + 1] - source.offsets[s];
      ASSERT_EQ(back.offsets[i + 1] - back.offsets[i], n) << name << " streamline " << i;
      EXPECT_TRUE(std::equal(source.positions.begin() + 3 * source.offsets[s],
                             source.positions.begin() + 3 * source.offsets[s + 1],
                             back.positions.begin() + 3 * back.offsets[i]))
          << name << " streamline " << i;
    }
    if (std::string(name) == "out.tck") continue;  // a TCK holds positions only
    ASSERT_EQ(back.point_values.size(), 1u) << name;
    for (std::size_t i = 0; i < kept.size(); ++i)
      EXPECT_EQ(back.point_values[0].values[back.offsets[i]], float(source.offsets[kept[i]])) << name;
    const bool vtk = std::string(name) == "out.vtk";
    ASSERT_EQ(back.streamline_values.size(), vtk ? 2u : 1u) << name;
    for (std::size_t i = 0; i < kept.size(); ++i)
      EXPECT_EQ(back.streamline_values[0].values[i], float(kept[i]) / 2) << name;
    if (vtk) {  // legacy VTK has no groups: the group is a 0/1 cell array, read back as values
      for (std::size_t i = 0; i < kept.size(); ++i)
        EXPECT_EQ(back.streamline_values[1].values[i], kept[i] % 2 == 1 ? 1.0f : 0.0f) << name;
      continue;
    }
    ASSERT_EQ(back.groups.size(), 1u) << name;
    std::vector<std::uint64_t> odd_kept;
    for (std::size_t i = 0; i < kept.size(); ++i)
      if (kept[i] % 2 == 1) odd_kept.push_back(i);
    EXPECT_EQ(back.groups[0].members, odd_kept) << name;
  }
}

TEST(SelectionOutputs, AnEmptySelectionWritesValidEmptyFiles) {
  ScratchDir dir;
  convert_tractogram(synth(50), dir.file("in.vxl"), settings(PositionEncoding::Packed));
  for (const char* name : {"e.tck", "e.trx", "e.vtk", "e.vxl"}) {
    const test::CommandResult r =
        run_cli("select " + test::q(dir.file("in.vxl")) + " " + test::q(dir.file(name)) + " --include 5000,0,0,1");
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
    EXPECT_NE(r.output.find("0 of 50 streamlines selected"), std::string::npos) << r.output;
    if (std::string(name) == "e.vxl") {
      EXPECT_TRUE(verify_vxl(dir.file(name)).valid) << verify_vxl(dir.file(name)).problem;
      EXPECT_EQ(VxlFile::open(dir.file(name)).meta().streamline_count, 0u);
    } else {
      EXPECT_EQ(read_tractogram(dir.file(name)).streamline_count(), 0u) << name;
    }
  }
}

// Packed positions move a point by up to the file's bound: a streamline whose deciding point lies that
// close to a region's surface may be decided differently. Count them on a realistic set and check that
// every one is explained by such a point.
TEST(SelectionPrecision, PackedPositionsFlipOnlyStreamlinesWithAPointAtTheSurface) {
  ScratchDir dir;
  const Tractogram source = synth(4000, 5);
  Tractogram a = source, b = source;
  convert_tractogram(std::move(a), dir.file("f32.vxl"), settings(PositionEncoding::Float32));
  convert_tractogram(std::move(b), dir.file("packed.vxl"), settings(PositionEncoding::Packed));
  const VxlFile exact = VxlFile::open(dir.file("f32.vxl")), packed = VxlFile::open(dir.file("packed.vxl"));
  double bound = 0;
  for (const VoxelEntry& v : packed.voxels()) bound = std::max(bound, packed_error_bound(v));
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> x(-60, 60), y(-90, 60), z(-40, 60);
  std::uint64_t flips = 0, selected = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const float cx = x(rng), cy = y(rng), cz = z(rng), r = 10;
    SelectionCriteria c;
    c.include.push_back(sphere(cx, cy, cz, r));
    const auto e = select_streamlines(exact, c).streamlines, p = select_streamlines(packed, c).streamlines;
    selected += e.size();
    std::vector<std::uint64_t> differ;
    std::set_symmetric_difference(e.begin(), e.end(), p.begin(), p.end(), std::back_inserter(differ));
    flips += differ.size();
    for (std::uint64_t s : differ) {
      double nearest = INFINITY;  // the distance of the streamline's nearest point to the sphere's surface
      for (std::uint64_t i = source.offsets[s]; i < source.offsets[s + 1]; ++i) {
        const float* q = &source.positions[3 * i];
        const double d =
            std::sqrt(std::pow(q[0] - double(cx), 2) + std::pow(q[1] - double(cy), 2) + std::pow(q[2] - double(cz), 2));
        nearest = std::min(nearest, std::abs(d - r));
      }
      EXPECT_LE(nearest, 2 * std::sqrt(3.0) * bound) << "streamline " << s << " flipped with no point near the surface";
    }
  }
  ASSERT_GT(selected, 1000u);
  std::printf("packed vs float32 positions: %llu flips in %llu selections of 60 spheres of 10 mm (bound %.2g mm)\n",
              (unsigned long long)flips, (unsigned long long)selected, bound);
  EXPECT_LE(double(flips), 0.002 * double(selected));
}

TEST(SelectionCli, CountJsonAndTheCriteriaInTheTckHeader) {
  ScratchDir dir;
  convert_tractogram(synth(300), dir.file("in.vxl"), settings(PositionEncoding::Float32));
  const std::string in = test::q(dir.file("in.vxl"));
  const test::CommandResult count = run_cli("select " + in + " --include 0,-18,10,20 --count");
  ASSERT_EQ(count.exit_code, 0) << count.output;
  const std::uint64_t n = std::stoull(count.output);
  EXPECT_GT(n, 0u);
  const test::CommandResult json = run_cli("select " + in + " --include 0,-18,10,20 --count --json");
  ASSERT_EQ(json.exit_code, 0) << json.output;
  EXPECT_EQ(nlohmann::json::parse(json.output)["selected"].get<std::uint64_t>(), n);
  // A count writes nothing: the options of a written TCK are refused with it, not ignored.
  for (const std::string& extra : {" --tsf " + test::q(dir.file("c.tsf")), std::string(" --value v")}) {
    const test::CommandResult refused = run_cli("select " + in + " --include 0,-18,10,20 --count" + extra);
    EXPECT_EQ(refused.exit_code, 2) << extra << ": " << refused.output;
    EXPECT_NE(refused.output.find("--count excludes " + extra.substr(1, extra.find(' ', 1) - 1)), std::string::npos)
        << refused.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("c.tsf")));
  }
  const test::CommandResult written =
      run_cli("select " + in + " " + test::q(dir.file("o.tck")) + " --include 0,-18,10,20 --exclude 0,0,0,1");
  ASSERT_EQ(written.exit_code, 0) << written.output;
  const Tractogram back = read_tractogram(dir.file("o.tck"));
  EXPECT_LE(back.streamline_count(), n);
  EXPECT_NE(back.source.header.dump().find("include 0,-18,10,20"), std::string::npos) << back.source.header.dump();
}

// --level in the CLI: the count is the API's, and the TCK header says how the selection was made.
TEST(SelectionCli, ALevelOfDetailIsCountedWrittenAndRecorded) {
  ScratchDir dir;
  convert_tractogram(synth(800), dir.file("in.vxl"), settings(PositionEncoding::Packed));
  const std::string in = test::q(dir.file("in.vxl"));
  SelectionCriteria c;
  c.level = 1;
  const std::uint64_t expected = select_streamlines(VxlFile::open(dir.file("in.vxl")), c).streamlines.size();
  const test::CommandResult count = run_cli("select " + in + " --level 1 --count");
  ASSERT_EQ(count.exit_code, 0) << count.output;
  EXPECT_EQ(std::stoull(count.output), expected);
  ASSERT_EQ(run_cli("select " + in + " " + test::q(dir.file("o.tck")) + " --level 1").exit_code, 0);
  const Tractogram back = read_tractogram(dir.file("o.tck"));
  EXPECT_EQ(back.streamline_count(), expected);
  EXPECT_NE(back.source.header.dump().find("level 1"), std::string::npos) << back.source.header.dump();
  const test::CommandResult beyond = run_cli("select " + in + " --level 5 --count");
  EXPECT_EQ(beyond.exit_code, 2);
  EXPECT_NE(beyond.output.find("--level"), std::string::npos) << beyond.output;
}

// One table of output formats (converter/export/streamline_outputs.h): select writes every suffix it lists and export
// every one it marks exported, and both commands' help and refusals list exactly those (select's omitted .trk).
TEST(SelectionCli, OutputSuffixesComeFromOneTable) {
  ScratchDir dir;
  convert_tractogram(synth(30), dir.file("in.vxl"), settings(PositionEncoding::Packed));
  for (const StreamlineOutputFormat& f : streamline_outputs())
    for (const std::string& suffix : f.suffixes) {
      const std::string out = dir.file("out" + suffix);
      EXPECT_EQ(run_cli("select " + test::q(dir.file("in.vxl")) + " " + test::q(out) + " --include 0,0,0,50").exit_code,
                0)
          << suffix;
      EXPECT_TRUE(std::filesystem::exists(out)) << suffix;
      std::filesystem::remove(out);
      EXPECT_EQ(run_cli("export " + test::q(dir.file("in.vxl")) + " " + test::q(out)).exit_code, f.exported ? 0 : 2)
          << suffix;
      EXPECT_EQ(std::filesystem::exists(out), f.exported) << suffix;
    }
  const test::CommandResult select = run_cli("select " + test::q(dir.file("in.vxl")) + " o.txt --include 0,0,0,5");
  EXPECT_EQ(select.exit_code, 2);
  EXPECT_NE(select.output.find("written to .tck, .trx, .vtk, .trk, .trk.gz or .vxl"), std::string::npos)
      << select.output;
  // Both help texts say what each format they write keeps, from the same table.
  const std::string select_help = run_cli("select --help").output, export_help = run_cli("export --help").output;
  for (const StreamlineOutputFormat& f : streamline_outputs()) {
    EXPECT_NE(select_help.find(f.suffixes.back() + " (" + f.keeps + ")"), std::string::npos) << f.suffixes[0];
    EXPECT_EQ(export_help.find(f.keeps) != std::string::npos, f.exported) << f.suffixes[0];
  }
  const test::CommandResult exported = run_cli("export " + test::q(dir.file("in.vxl")) + " o.txt");
  EXPECT_EQ(exported.exit_code, 2);
  EXPECT_NE(exported.output.find("export writes .tck, .trx, .vtk, .trk or .trk.gz files"), std::string::npos)
      << exported.output;
}

// A mask named 64 times is read once and its voxels kept once, cropped to what is set: a 256³ image's 16.7M
// voxels kept whole for each of 64 regions would take over 1 GiB. The limit on regions is checked before any file
// is read: a 65th region naming no file is refused for the count.
TEST(SelectionCli, AMaskNamedSixtyFourTimesIsReadOnceAndTheLimitComesFirst) {
  ScratchDir dir;
  convert_tractogram(synth(300), dir.file("in.vxl"), settings(PositionEncoding::Float32));
  std::string voxels(std::size_t(256) * 256 * 256, '\0');
  for (std::size_t k = 108; k < 148; ++k)
    for (std::size_t j = 108; j < 148; ++j)
      for (std::size_t i = 108; i < 148; ++i) voxels[i + 256 * (j + 256 * k)] = 1;
  std::ofstream(dir.file("m.nii"), std::ios::binary)
      << test::nifti1_bytes({256, 256, 256}, DT_UINT8, 8, voxels, {1, 0, 0, -128, 0, 1, 0, -128, 0, 0, 1, -128});
  std::string many, one = " --include " + test::q(dir.file("m.nii"));
  for (int i = 0; i < 64; ++i) many += one;
  const std::string in = test::q(dir.file("in.vxl"));
  const test::CommandResult once = run_cli("select " + in + " --count" + one);
  ASSERT_EQ(once.exit_code, 0) << once.output;
  EXPECT_GT(std::stoull(once.output), 0u);
  const test::CommandResult sixty_four = run_cli("select " + in + " --count" + many);
  ASSERT_EQ(sixty_four.exit_code, 0) << sixty_four.output;
  EXPECT_EQ(sixty_four.output, once.output);
  if (!test::kAddressSanitizer) {
    rusage children{};
    getrusage(RUSAGE_CHILDREN, &children);
    EXPECT_LT(children.ru_maxrss, 400 << 10) << "KiB: the mask was kept once per region";
  }
  const test::CommandResult too_many =
      run_cli("select " + in + " --count" + many + " --include " + test::q(dir.file("absent.nii")));
  EXPECT_EQ(too_many.exit_code, 2) << too_many.output;
  EXPECT_NE(too_many.output.find("at most 64 regions in one selection (65 given)"), std::string::npos)
      << too_many.output;

  const std::vector<Region> together = parse_regions({dir.file("m.nii"), "1,2,3,4", dir.file("m.nii")});
  ASSERT_EQ(together.size(), 3u);
  EXPECT_EQ(together[1].shape(), Region::Shape::Sphere);
  const float inside[3] = {0, 0, 0}, outside[3] = {30, 0, 0};
  for (const std::size_t r : {0u, 2u}) {
    EXPECT_EQ(together[r].shape(), Region::Shape::Mask);
    EXPECT_TRUE(together[r].contains(inside));
    EXPECT_FALSE(together[r].contains(outside));
  }
}

// An image this process cannot hold is refused naming the file and the limit (exit 4), not "out of memory" or
// "cannot map": under a 1 GiB address-space limit, a 512 MiB uint8 mask (2 GiB as float32 samples) and a 2 GiB
// float64 one (which cannot be mapped). Both files are sparse.
TEST(SelectionCli, AnImageBeyondTheMemoryLimitIsRefusedNamingTheFileAndTheLimit) {
  if (test::kAddressSanitizer) GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit";
  ScratchDir dir;
  convert_tractogram(synth(50), dir.file("in.vxl"), settings(PositionEncoding::Float32));
  for (const auto& [name, datatype, bits] :
       {std::tuple{"u8.nii", DT_UINT8, 8}, std::tuple{"f64.nii", DT_FLOAT64, 64}}) {
    const std::string path = dir.file(name);
    std::ofstream(path, std::ios::binary) << test::nifti1_bytes({1024, 1024, 512}, datatype, bits, "");
    std::filesystem::resize_file(path, 352 + std::uintmax_t(1024) * 1024 * 512 * (bits / 8));
    const test::CommandResult r = test::run_program(
        "/bin/sh", "-c 'ulimit -v 1048576 && exec \"$0\" \"$@\"' " + test::q(VOXLINES_CLI) + " select " +
                       test::q(dir.file("in.vxl")) + " --count --include " + test::q(path));
    EXPECT_EQ(r.exit_code, 4) << name << ": " << r.output;
    EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("address-space limit (ulimit -v) of 1.0 GiB"), std::string::npos) << r.output;
  }
}

TEST(SelectionCli, HostileRegionsAreRefusedNamingTheArgumentAndWriteNothing) {
  ScratchDir dir;
  convert_tractogram(synth(50), dir.file("in.vxl"), settings(PositionEncoding::Packed));
  test::write_file(dir.file("text.nii"), {'n', 'o', 't', ' ', 'n', 'i', 'f', 't', 'i'});
  std::vector<std::int16_t> one(8, 0);
  one[3] = 2;
  test::write_nifti_int16(dir.file("atlas.nii.gz"), {2, 2, 2}, one, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0});
  // A .nii.gz whose header claims 2^16 x 2^16 x 2^10 voxels: refused from the header, before inflating.
  std::vector<std::int16_t> tiny(8, 1);
  test::write_nifti_int16(dir.file("huge.nii.gz"), {2, 2, 2}, tiny, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0});
  {
    // Patch dim[1..3] (bytes 42..47 of the uncompressed header) through zlib.
    std::vector<char> raw;
    gzFile in = gzopen(dir.file("huge.nii.gz").c_str(), "rb");
    char buf[4096];
    for (int n; (n = gzread(in, buf, sizeof buf)) > 0;) raw.insert(raw.end(), buf, buf + n);
    gzclose(in);
    const std::int16_t dims[3] = {32767, 32767, 1024};
    std::memcpy(raw.data() + 42, dims, sizeof dims);
    gzFile out = gzopen(dir.file("huge.nii.gz").c_str(), "wb");
    gzwrite(out, raw.data(), unsigned(raw.size()));
    gzclose(out);
  }
  struct Case {
    std::string region;
    int code;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"0,0,0,-1", 2, "radius is negative"},
      {"0,0,0,nan", 2, "finite"},
      {"0,0,inf,3", 2, "finite"},
      {"0,0,3", 2, "X,Y,Z,R"},
      {"box:0,0,0,-1,5,5", 2, "below its second"},
      {"box:0,0,0,1,1", 2, "box:X0"},
      {dir.file("text.nii"), 3, "not a NIfTI file"},
      {dir.file("atlas.nii.gz") + ":9", 2, "no voxel of label 9"},
      {dir.file("missing.nii.gz"), 2, "no such image file"},
      {dir.file("huge.nii.gz"), 4, "voxels"},
      {"nonsense", 2, "expected X,Y,Z,R"},
  };
  for (const Case& c : cases) {
    const std::string out = dir.file("out.tck");
    const test::CommandResult r =
        run_cli("select " + test::q(dir.file("in.vxl")) + " " + test::q(out) + " --include " + test::q(c.region));
    EXPECT_EQ(r.exit_code, c.code) << c.region << ": " << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << c.region << ": " << r.output;
    EXPECT_NE(r.output.find(c.region.substr(0, 20)), std::string::npos) << "the message must name the argument";
    EXPECT_FALSE(std::filesystem::exists(out)) << c.region;
  }
  const test::CommandResult lengths =
      run_cli("select " + test::q(dir.file("in.vxl")) + " --count --min-length 50 --max-length 10");
  EXPECT_EQ(lengths.exit_code, 2) << lengths.output;
  const test::CommandResult no_output = run_cli("select " + test::q(dir.file("in.vxl")) + " --include 0,0,0,5");
  EXPECT_EQ(no_output.exit_code, 2) << no_output.output;
  const test::CommandResult wrong_extension =
      run_cli("select " + test::q(dir.file("in.vxl")) + " " + test::q(dir.file("o.trk.xz")) + " --include 0,0,0,5");
  EXPECT_EQ(wrong_extension.exit_code, 2) << wrong_extension.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("o.trk.xz")));
}

}  // namespace
}  // namespace vxl
