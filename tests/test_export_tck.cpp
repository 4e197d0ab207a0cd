// A TCK export keeps the source TCK header's properties as tckedit does (so that MRtrix tools reading it,
// tcksift or length thresholds, see the tracking's step size, lengths, ROIs and history), leaves out the
// keys the writer owns, and adds nothing for sources of other formats.
#include <cmath>
#include <limits>

#include "converter/convert/convert.h"
#include "converter/export/export_tck.h"
#include "converter/export/tck_writer.h"
#include "converter/readers/mrtrix_header.h"
#include "converter/readers/read_tractogram.h"
#include "converter/synth/synth.h"
#include "format/vxl_file.h"
#include "tests/mrtrix_test_files.h"
#include "tests/test_support.h"

namespace vxl {
namespace {

using test::ScratchDir;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN(), kInf = std::numeric_limits<float>::infinity();

// A tckgen-like source: repeated keys (roi, command_history), a timestamp, an empty ROI (as a real file has:
// MRtrix crashes on it, so it is not carried).
std::string tracked_tck(const ScratchDir& dir) {
  const std::string path = dir.file("tracked.tck");
  test::write_mrtrix_file(path, "mrtrix tracks", "Float32LE",
                          test::raw<float>({0, 0, 0, 1, 0, 0, 2,    0,    0,    kNaN, kNaN, kNaN,
                                            0, 1, 0, 0, 2, 0, kNaN, kNaN, kNaN, kInf, kInf, kInf}),
                          "command_history: tckgen fod.mif out.tck -select 2\n"
                          "command_history: tckedit out.tck tracked.tck\n"
                          "count: 2\ntotal_count: 1000\nmax_dist: 250\nmin_dist: 10\nmethod: iFOD2\n"
                          "step_size: 0.625\nroi: seed mask.mif\nroi: \nroi: include sphere 1,2,3,4\n"
                          "source: fod.mif\ntimestamp: 1658253059.7624535561\n");
  return path;
}

VxlFile converted(Tractogram t, const std::string& path) {
  convert_tractogram(std::move(t), path, {});
  return VxlFile::open(path);
}

MrtrixHeader header_of(const std::string& path) {
  const std::vector<char> bytes = test::slurp(path);
  return parse_mrtrix_header(path, {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, kTckFile);
}

nlohmann::json values(std::initializer_list<const char*> v) {
  nlohmann::json a = nlohmann::json::array();
  for (const char* s : v) a.push_back(s);
  return a;
}

// Told the points up front, a TCK (or TSF) is written past the page cache by a queue of its own: the same bytes as
// written through the page cache, also when the streamlines outgrow several of its stagings; told more points
// than it is given, it refuses to commit, and nothing appears at the path.
TEST(TckWriter, KnowingItsSizeItWritesTheSameBytesPastThePageCache) {
  ScratchDir dir;
  SynthSettings synth;
  synth.streamlines = 30000;  // about 20 MB: several 4 MiB stagings
  const Tractogram t = synthesize_tractogram(synth);
  auto write = [&](const std::string& path, std::optional<std::uint64_t> points) {
    TckWriter w(path, t.streamline_count(), {"note: one"}, points);
    for (std::uint64_t i = 0; i < t.streamline_count(); ++i)
      w.add(std::span<const float>(t.positions.data() + 3 * t.offsets[i], 3 * (t.offsets[i + 1] - t.offsets[i])));
    w.finish();
  };
  write(dir.file("buffered.tck"), std::nullopt);
  write(dir.file("direct.tck"), t.point_count());
  const std::vector<char> buffered = test::slurp(dir.file("buffered.tck"));
  ASSERT_GT(buffered.size(), 16u << 20);
  EXPECT_TRUE(buffered == test::slurp(dir.file("direct.tck")));
  EXPECT_THROW(write(dir.file("short.tck"), t.point_count() + 1), std::logic_error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("short.tck")));
}

TEST(ExportTck, KeepsTheSourceHeaderProperties) {
  ScratchDir dir;
  TckExportSettings settings;
  settings.tsf_path = dir.file("t.tsf");
  Tractogram with_values = read_tck(tracked_tck(dir));
  with_values.point_values.push_back({"v", {1, 2, 3, 4, 5}});
  const VxlFile fv = converted(std::move(with_values), dir.file("tv.vxl"));
  export_tck(fv, dir.file("t.tck"), settings);
  {
    const MrtrixHeader h = header_of(dir.file("t.tck"));
    EXPECT_EQ(h.fields["step_size"], values({"0.625"}));
    EXPECT_EQ(h.fields["max_dist"], values({"250"}));
    EXPECT_EQ(h.fields["min_dist"], values({"10"}));
    EXPECT_EQ(h.fields["method"], values({"iFOD2"}));
    EXPECT_EQ(h.fields["source"], values({"fod.mif"}));
    EXPECT_EQ(h.fields["command_history"], values({"tckgen fod.mif out.tck -select 2", "tckedit out.tck tracked.tck"}));
    // As tckedit: the source's ROIs are prior ones; count is the writer's; total_count is not carried.
    EXPECT_EQ(h.fields["prior_roi"], values({"seed mask.mif", "include sphere 1,2,3,4"}));
    EXPECT_FALSE(h.fields.contains("roi"));
    EXPECT_FALSE(h.fields.contains("total_count"));
    EXPECT_EQ(h.fields["count"], values({"2"}));
    EXPECT_EQ(h.fields["datatype"], values({"Float32LE"}));
    EXPECT_EQ(h.fields["timestamp"], values({"1658253059.7624535561"}));
  }
  // The TSF carries the same timestamp (MRtrix checks it against its tractogram's).
  const std::vector<char> tsf = test::slurp(dir.file("t.tsf"));
  const MrtrixHeader th =
      parse_mrtrix_header(dir.file("t.tsf"), {reinterpret_cast<const std::uint8_t*>(tsf.data()), tsf.size()}, kTsfFile);
  EXPECT_EQ(th.fields["timestamp"], values({"1658253059.7624535561"}));
  // And our reader takes the export back, header and all.
  const Tractogram back = read_tck(dir.file("t.tck"));
  EXPECT_EQ(back.streamline_count(), 2u);
  EXPECT_EQ(back.source.header["step_size"], values({"0.625"}));
}

TEST(ExportTck, SelectionHeaderLinesReplaceTheSourcesKeys) {
  ScratchDir dir;
  const VxlFile f = converted(read_tck(tracked_tck(dir)), dir.file("t.vxl"));
  const StreamlineSubset subset(2, {1});
  export_tck(f, dir.file("s.tck"), {}, &subset, {"roi: include 0,1,0,1", "min_dist: 1.5"});
  const MrtrixHeader h = header_of(dir.file("s.tck"));
  EXPECT_EQ(h.fields["min_dist"], values({"1.5"}));
  EXPECT_EQ(h.fields["max_dist"], values({"250"}));
  EXPECT_EQ(h.fields["roi"], values({"include 0,1,0,1"}));
  EXPECT_EQ(h.fields["prior_roi"], values({"seed mask.mif", "include sphere 1,2,3,4"}));
  EXPECT_EQ(h.fields["count"], values({"1"}));
}

TEST(ExportTck, OtherSourcesGetNoTckProperties) {
  ScratchDir dir;
  SynthSettings s;
  s.streamlines = 5;
  Tractogram t = synthesize_tractogram(s);
  t.source.format = "trk";
  t.source.header = {{"step_size", values({"9"})}, {"timestamp", values({"1"})}};
  export_tck(converted(std::move(t), dir.file("t.vxl")), dir.file("t.tck"));
  const MrtrixHeader h = header_of(dir.file("t.tck"));
  for (const auto& [key, v] : h.fields.items())
    EXPECT_TRUE(key == "datatype" || key == "count" || key == "file" || key == "voxlines_exported_from") << key;
}

}  // namespace
}  // namespace vxl
