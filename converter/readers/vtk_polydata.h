// What the legacy VTK and the XML VTP readers share: the decoded pieces of a POLYDATA (points, line
// cells, point and cell data arrays) and their assembly into a Tractogram.
//
// Not VTK itself: Debian's libvtk9-dev pulls in hundreds of MB of libraries for what is here a few hundred
// lines of parsing; the XML is parsed by pugixml and compressed blocks are inflated by zlib.
//
// Coordinates are taken as written, as RAS mm (VTK has no coordinate system of its own; tckconvert,
// whitematteranalysis, UKF and NiiVue write RAS). The one exception is 3D Slicer's hint: a legacy title
// line or an XML comment saying `SPACE=LPS` (Slicer 4.11+ writes models in LPS by default) makes the reader
// negate x and y, as Slicer does when it loads the file; `SPACE=RAS` and no hint leave the points unchanged.
//
// Arrays become value sets: one component -> a set named after the array; 2 to 4 components (colours,
// vectors) -> one set per component, `name[0]`, `name[1]`, ...; more components (tensors, embeddings) and
// string or bit arrays are skipped with a warning. Integer arrays are widened to float (exact to 2^24).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "converter/tractogram.h"

namespace vxl::vtk {

// Arrays with more components than this are skipped with a warning.
inline constexpr std::uint64_t kMaxComponentsKept = 4;

struct DataArray {
  std::string name;
  std::uint64_t components = 1;
  std::vector<double> values;  // tuples * components, tuple-major
};

struct PolyData {
  std::vector<double> points;  // 3 per point
  std::uint64_t point_count = 0;
  // Line cells: cell k uses connectivity[offsets[k] .. offsets[k+1]); offsets starts at 0.
  std::vector<std::uint64_t> line_offsets{0};
  std::vector<double> line_connectivity;
  std::uint64_t cells_before_lines = 0;  // vertex cells: cell data lists them first
  std::uint64_t cell_count = 0;          // every cell (verts, lines, polys, strips), for cell data sizes
  std::vector<DataArray> point_data, cell_data;
};

// Fills t's streamlines (one per line cell, its points gathered through the connectivity) and value
// sets from `p`, checking every index and array size; throws vxl::Error (Input) naming `path`.
void fill_tractogram(Tractogram& t, const std::string& path, const PolyData& p, bool lps);

// The provenance of a tractogram read from `bytes`, the whole file at `path`, in format `format`.
void describe_source(Tractogram& t, const std::string& path, const char* format, std::span<const std::uint8_t> bytes);

// A legacy array name with VTK's %XX escapes (for blanks and '%') decoded.
std::string decode_name(const std::string& name);

// True when the text carries Slicer's `SPACE=LPS` hint.
bool says_lps(const std::string& text);

// Byte-order helpers.
std::uint64_t load_uint(const std::uint8_t* p, unsigned size, bool big_endian);
double load_number(const std::uint8_t* p, char kind, unsigned size, bool big_endian);  // kind: 'i' 'u' 'f'

}  // namespace vxl::vtk
