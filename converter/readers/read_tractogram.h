// Source readers. Each fills the neutral Tractogram (RAS mm, float32) and the SourceInfo provenance,
// and throws vxl::Error naming the file, the byte offset and what was expected on malformed input.
//
//   TCK  (MRtrix):   read_tck.cpp   — Float32/64, LE/BE; NaN ends a streamline, Inf the file.
//   TRK  (TrackVis): read_trk.cpp   — v1/v2, either endianness, voxmm -> RAS, .trk.gz.
//   TRX:             read_trx.cpp   — zip (stored/deflated) or directory; float16/32/64; uint32/64
//                                     offsets with or without the sentinel; groups kept.
//   VTK (legacy):    read_vtk.cpp   — POLYDATA LINES, ASCII or BINARY (big-endian), classic or 5.1 cells.
//   VTP (VTK XML):   read_vtp.cpp   — PolyData Lines; ascii, base64, appended raw/base64, zlib blocks.
//                    (vtk_polydata.h: what both keep as value sets, and the coordinate convention.)
#pragma once

#include <string>

#include "converter/tractogram.h"

namespace vxl {

Tractogram read_tck(const std::string& path);
Tractogram read_trk(const std::string& path);
Tractogram read_trx(const std::string& path);
Tractogram read_vtk(const std::string& path);
Tractogram read_vtp(const std::string& path);

// Chooses the reader from the file name (source_formats.h); throws an Unsupported error for anything else
// (e.g. .tsf) that says what is supported.
Tractogram read_tractogram(const std::string& path);

}  // namespace vxl
