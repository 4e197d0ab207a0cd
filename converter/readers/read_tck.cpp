// TCK reader (MRtrix3 tracks file).
//
// Coordinate convention: TCK stores world coordinates, RAS mm, as-is; we convert to float32 (exact for
// Float32 files, rounded to nearest for Float64 files: spec §8).
//
// Layout: text header "mrtrix tracks" / "key: value" lines (keys may repeat) / "END"; the data starts at
// the byte offset in "file: . OFFSET". Data: xyz triplets; a triplet whose x is NaN ends a streamline, one
// whose x is Inf ends the file. Like MRtrix we tolerate a missing Inf terminator at EOF, and trust the data
// over a stale "count"; unlike MRtrix we warn about data it ignores (after the terminator, or cut by an Inf
// x that is no whole terminator).
#include "converter/readers/read_tractogram.h"
#include "converter/readers/regular_file.h"
#include "converter/readers/tck_format.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/mapped_file.h"

namespace vxl {
namespace tck {

void finish(const DecodeState& s, std::uint64_t trailing, Tractogram& t, std::vector<std::string>& warnings) {
  if (!s.terminated) {
    std::string w = "no Inf terminator before end of file (tolerated, as MRtrix does)";
    if (trailing != 0) w += "; " + std::to_string(trailing) + " trailing bytes ignored";
    warnings.push_back(w);
    if (s.points_in_current > 0) {
      t.offsets.push_back(t.point_count());
      warnings.push_back("last streamline (" + std::to_string(s.points_in_current) +
                         " points) has no NaN delimiter: kept");
    }
  } else {
    // MRtrix ignores all this silently; we warn, as the user loses data.
    if (s.partial_terminator)
      warnings.push_back("the data ends at byte " + std::to_string(*s.partial_terminator) +
                         " at a point whose x is Inf but which is not the terminator (Inf, Inf, Inf): the point and "
                         "everything after it are ignored");
    if (trailing != 0) warnings.push_back(std::to_string(trailing) + " bytes after the Inf terminator ignored");
    // MRtrix writes a NaN before the Inf; without it the points still form a streamline.
    if (s.points_in_current > 0) t.offsets.push_back(t.point_count());
  }
}

void header_warnings(const MrtrixHeader& h, std::uint64_t streamlines, std::vector<std::string>& warnings) {
  if (h.datatype.starts_with("Float64")) warnings.push_back("Float64 coordinates rounded to float32 (spec §8)");
  if (auto w = count_warning(h, streamlines)) warnings.push_back(*w);
}

}  // namespace tck

namespace {

// Walks all data triplets into t.
template <typename Real, bool kBigEndian>
void read_points(const std::string& path, std::span<const std::uint8_t> bytes, std::uint64_t offset, Tractogram& t) {
  constexpr std::size_t kTriplet = 3 * sizeof(Real);
  const std::uint64_t available = (bytes.size() - offset) / kTriplet;
  t.positions.reserve(3 * available);
  tck::DecodeState s;
  const std::uint64_t used =
      tck::decode<Real, kBigEndian>(path, bytes.data() + offset, available, offset, t, s, ~std::uint64_t(0));
  tck::finish(s, bytes.size() - offset - used * kTriplet, t, t.source.warnings);
}

}  // namespace

Tractogram read_tck(const std::string& path) {
  require_regular_file(path);
  MappedFile file(path);
  const MrtrixHeader h = parse_mrtrix_header(path, file.bytes(), kTckFile);
  Tractogram t;
  t.source.path = path;
  t.source.format = "tck";
  t.source.dtype = h.datatype;
  t.source.bytes = file.size();
  t.source.xxh3_128 = xxh3_128_hex(file.data(), file.size());
  t.source.header = h.fields;

  const MrtrixDatatype type = mrtrix_datatype(path, h.datatype, kTckFile);
  visit_mrtrix_datatype(type, [&]<typename Real, bool kBigEndian>() {
    read_points<Real, kBigEndian>(path, file.bytes(), h.data_offset, t);
  });

  tck::header_warnings(h, t.streamline_count(), t.source.warnings);
  return t;
}

}  // namespace vxl
