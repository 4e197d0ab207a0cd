#include "converter/package/pack.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

#include "converter/convert/voxelize.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/base/parallel.h"
#include "format/vxl_streamlines.h"
#include "format/vxlz_draco.h"
#include "format/vxlz_package.h"
#include "format/vxlz_quantize.h"
#include "format/vxlz_shipping_order.h"
#include "format/vxlz_tables.h"
#include "format/vxlz_values.h"

namespace vxl {
namespace {

// Where each voxline's points are: its first vertex in VERT and its first shipped point (spec §5.1).
struct VoxlineIndex {
  std::vector<std::uint64_t> first_vertex;      // L
  std::vector<std::uint64_t> first_point;       // L + 1, prefix sums of own counts
  std::vector<std::uint8_t> starts_streamline;  // L
};

VoxlineIndex index_voxlines(const VxlFile& f) {
  VoxlineIndex x;
  const std::uint64_t l = f.meta().voxline_count;
  x.first_vertex.reserve(l);
  // The walk checks the voxline and streamline tables (ranges, blocks consumed exactly, connecting
  // vertices equal to the next first point, totals) before anything relies on them.
  WalkCallbacks cb;
  cb.voxline = [&](const VoxlineVisit& v) { x.first_vertex.push_back(v.first_vertex); };
  walk_streamlines(f, cb);
  x.first_point.resize(l + 1);
  x.first_point[0] = 0;
  for (std::uint64_t j = 0; j < l; ++j)
    x.first_point[j + 1] = x.first_point[j] + (f.voxlines()[j].count_flags & kVoxlineCountMask);
  x.starts_streamline.assign(l, 0);
  auto strm = f.streamline_first_voxline();
  for (std::uint64_t s = 0; s + 1 < strm.size(); ++s)
    if (strm[s] < strm[s + 1]) x.starts_streamline[strm[s]] = 1;
  return x;
}

// The per-vertex value sets as values per shipped point (spec §4.7): each voxline's own vertices. A
// connecting vertex's value is not shipped: the unpacker copies the next voxline's first value, so it
// must be that value, bit for bit, for the round trip to be exact.
std::vector<NamedValues> shipped_point_values(const VxlFile& f, const VoxlineIndex& index) {
  const ValueSets& sets = f.vertex_values();
  auto voxlines = f.voxlines();
  const std::uint64_t l = voxlines.size();
  std::vector<NamedValues> out(sets.size());
  for (std::uint32_t k = 0; k < sets.size(); ++k) {
    const std::span<const float> v = sets.values(k);
    out[k].name = sets.name(k);
    out[k].values.resize(index.first_point.back());
    float* dst = out[k].values.data();
    for (std::uint64_t j = 0; j < l; ++j) {
      const std::uint64_t own = voxlines[j].count_flags & kVoxlineCountMask;
      const std::uint64_t first = index.first_vertex[j];
      std::copy(v.begin() + first, v.begin() + first + own, dst + index.first_point[j]);
      if (j + 1 < l && !index.starts_streamline[j + 1] &&
          std::memcmp(&v[first + own], &v[index.first_vertex[j + 1]], 4) != 0)
        fail_input(
            f.path(), f.find_section(section_id("VVAL"))->offset,
            "value set '" + out[k].name + "': a connecting vertex's value differs from the next voxline's first");
    }
  }
  return out;
}

std::vector<NamedValues> streamline_values(const ValueSets& sets) {
  std::vector<NamedValues> out(sets.size());
  for (std::uint32_t k = 0; k < sets.size(); ++k) {
    out[k].name = sets.name(k);
    out[k].values.assign(sets.values(k).begin(), sets.values(k).end());
  }
  return out;
}

// Every vertex is a shipped point or a copy of one, so the vertices' box is the shipped points' box.
// Returns false when a coordinate is not finite (the converter never writes one; quantising it would be
// meaningless). Read voxel by voxel, so that packed positions are decoded a block at a time.
bool vertex_box(const VxlFile& f, unsigned threads, double lo[3], double hi[3]) {
  auto voxels = f.voxels();
  std::vector<std::array<float, 6>> partial(threads, {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY});
  std::vector<std::uint8_t> finite(threads, 1);
  std::vector<std::vector<float>> blocks(threads);
  parallel_for(voxels.size(), threads, [&](std::uint64_t i, unsigned t) {
    auto& b = partial[t];
    std::vector<float>& xyz = blocks[t];
    xyz.resize(3 * std::uint64_t(voxels[i].vertex_count));
    f.read_vertices(i, voxels[i].vertex_first, voxels[i].vertex_count, xyz.data());
    bool ok = true;
    for (std::size_t k = 0; k < xyz.size(); k += 3)
      for (int c = 0; c < 3; ++c) {
        const float v = xyz[k + c];
        ok &= std::isfinite(v);
        b[c] = std::min(b[c], v);
        b[c + 3] = std::max(b[c + 3], v);
      }
    finite[t] &= ok;
  });
  for (int c = 0; c < 3; ++c) {
    lo[c] = hi[c] = 0;
    if (voxels.empty()) continue;
    lo[c] = INFINITY;
    hi[c] = -INFINITY;
    for (const auto& b : partial) {
      lo[c] = std::min(lo[c], double(b[c]));
      hi[c] = std::max(hi[c], double(b[c + 3]));
    }
  }
  return std::all_of(finite.begin(), finite.end(), [](std::uint8_t x) { return x != 0; });
}

// The joint symbol width t (spec §5.3) for this package: the format lets the writer choose, and the best
// one grows with the residuals, so with the quantisation bits and with how curved and densely sampled
// the streamlines are. Encodes the first chunk with each candidate; among those within 1 % of the
// smallest, keeps the one that should decode fastest. Draco decodes a symbol in about 12 ns while it has
// at most 1024 distinct symbols, 15 ns up to 8192 and 22 ns beyond (its decoding table grows with
// them), and each escaped point costs about 30 ns more. Those figures were measured on this project's
// 2-core machine (1M set at 11, 14 and 16 bits, stroke at 14), where this rule picks the fastest t in each
// case: 16 bits took 25.5 ns per point with t = 4 against 35.7 with t = 2 (87 % escapes) at 1 % less
// size. The estimate only steers the choice; it never changes what is stored.
template <typename SampleFn>
std::uint32_t pick_joint_bits(bool has_points, SampleFn&& first_chunk_residuals) {
  constexpr std::uint32_t kDefault = 3;
  if (!has_points) return kDefault;
  std::vector<std::int32_t> sample;
  first_chunk_residuals(sample);
  const double points = double(sample.size() / 3);
  struct Candidate {
    std::uint32_t t;
    std::uint64_t size;
    double nanoseconds_per_point;
  };
  std::vector<Candidate> candidates;
  std::uint64_t best_size = ~std::uint64_t(0);
  std::vector<std::uint8_t> seen;
  for (std::uint32_t t = 2; t <= kVxlzMaxJointBits; ++t) {
    const EncodedChunk e = encode_residual_chunk(sample, t);
    seen.assign((1u << 3 * t) + 1, 0);
    std::uint64_t distinct = 0, escaped = 0;
    for (std::size_t i = 0; i + 3 <= sample.size(); i += 3) {
      const std::uint32_t symbol = joint_symbol(sample.data() + i, t);
      distinct += !seen[symbol];
      seen[symbol] = 1;
      escaped += symbol == 0;
    }
    const double per_symbol = distinct <= 1024 ? 12 : distinct <= 8192 ? 15 : 22;
    candidates.push_back({t, e.symbols.size() + e.escapes.size(), per_symbol + 30 * double(escaped) / points});
    best_size = std::min(best_size, candidates.back().size);
  }
  std::uint32_t pick = kDefault;
  double fastest = INFINITY;
  for (const Candidate& c : candidates)
    if (double(c.size) <= 1.01 * double(best_size) && c.nanoseconds_per_point < fastest) {
      pick = c.t;
      fastest = c.nanoseconds_per_point;
    }
  return pick;
}

// Quantisation grid (spec §3, §5.1): one cube over all shipped points (`n` of them).
PackSection plan_quantisation(const VxlFile& f, const PackSettings& settings, std::uint64_t n, unsigned threads) {
  PackSection pack{};
  pack.quantization_bits = settings.bits;
  // A file with levels ships the coarsest level's points first, so that a reader can show it before the rest.
  const std::uint32_t levels = f.meta().level_count;
  pack.predictor = levels > 1 ? kVxlzPredictorLinearLevelOrder : kVxlzPredictorLinear;
  pack.level_count = levels > 1 ? levels : 0;
  double hi[3];
  if (!vertex_box(f, threads, pack.quant_origin, hi))
    fail_input(f.path(), f.find_section(section_id("VERT"))->offset, "a vertex coordinate is not finite");
  pack.range = std::max({hi[0] - pack.quant_origin[0], hi[1] - pack.quant_origin[1], hi[2] - pack.quant_origin[2]});
  pack.quantum = pack.range > 0 ? pack.range / double((1u << settings.bits) - 1) : 1.0;
  if (!std::isfinite(pack.quantum) || !(pack.quantum > 0))
    throw Error(ErrorKind::Unsupported, f.path(), std::nullopt, "coordinate range too large to quantise");
  pack.point_count = n;
  pack.chunk_points = settings.chunk_points;
  pack.chunk_count = n / settings.chunk_points + (n % settings.chunk_points != 0);
  pack.error_bound = vxlz_error_bound(pack.quant_origin, pack.range, pack.quantum);
  return pack;
}

// The positions (spec §5): every chunk quantised, predicted and encoded, in parallel (chunks are
// independent); sets PACK's joint bits and error statistics.
void encode_positions(const VxlFile& f, const VoxlineIndex& index, unsigned threads, VxlzContent& c) {
  PackSection& pack = c.pack;
  const std::uint64_t n = pack.point_count;
  const Quantizer quantizer(pack);
  auto voxlines = f.voxlines();
  struct ErrorStats {
    double max = 0, sum_squares = 0;
  };
  // The points in the order they are shipped (spec §5.1): with levels, the coarsest level's streamlines first.
  const auto strm = f.streamline_first_voxline();
  const ShippingOrder order = shipping_order(strm, voxlines, shipped_depths(pack, f.meta().streamline_count));
  // Chunk `chunk`'s residuals (spec §5.2) into `residuals`, its quantisation errors into `e`.
  auto chunk_residuals = [&](std::uint64_t chunk, std::vector<std::int32_t>& residuals, ErrorStats& e) {
    const std::uint64_t start = chunk * pack.chunk_points;
    const std::uint64_t count = std::min(pack.chunk_points, n - start);
    residuals.resize(3 * count);
    ShippedVoxlineCursor at(order, strm, voxlines, start);
    LinearPredictor predictor;
    predictor.reset();
    std::vector<float> points;  // the current voxline's own points, decoded from its voxel's block
    for (std::uint64_t i = 0; i < count;) {
      const std::uint64_t j = at.voxline(), from = at.point_in_voxline(), own = at.own();
      points.resize(3 * own);
      f.read_vertices(voxlines[j].voxel, index.first_vertex[j], own, points.data());
      const std::uint64_t run = std::min(own - from, count - i);
      for (std::uint64_t r = 0; r < run; ++r) {
        if (from + r == 0 && index.starts_streamline[j]) predictor.start_streamline();
        const float* p = points.data() + 3 * (from + r);
        std::array<std::int64_t, 3> k;
        for (int a = 0; a < 3; ++a) {
          k[a] = quantizer.quantize(p[a], a);
          residuals[3 * (i + r) + a] = static_cast<std::int32_t>(k[a] - predictor.predict(a));
          const double error = std::abs(double(quantizer.dequantize(k[a], a)) - double(p[a]));
          e.max = std::max(e.max, error);
          e.sum_squares += error * error;
        }
        predictor.push(k);
      }
      i += run;
      at.advance(run);
    }
  };
  std::vector<std::vector<std::int32_t>> residuals(threads);  // one per thread, reused across chunks
  pack.joint_bits = pick_joint_bits(pack.chunk_count > 0, [&](std::vector<std::int32_t>& sample) {
    ErrorStats ignored;
    chunk_residuals(0, sample, ignored);
  });
  c.chunks.resize(pack.chunk_count);
  // Per chunk, summed in chunk order below: summed per thread, the RMS error's last bits (stored in PACK
  // and in the unpacked file's provenance) depended on which thread took which chunk.
  std::vector<ErrorStats> errors(pack.chunk_count);
  parallel_for(pack.chunk_count, threads, [&](std::uint64_t chunk, unsigned t) {
    ErrorStats e;  // local: neighbouring entries of `errors` share cache lines
    chunk_residuals(chunk, residuals[t], e);
    c.chunks[chunk] = encode_residual_chunk(residuals[t], pack.joint_bits);
    errors[chunk] = e;
  });
  double sum_squares = 0;
  for (const ErrorStats& e : errors) {
    pack.max_error = std::max(pack.max_error, e.max);
    sum_squares += e.sum_squares;
  }
  pack.rms_error = n > 0 ? std::sqrt(sum_squares / (3.0 * double(n))) : 0.0;
}

}  // namespace

PackSummary pack_vxl(const VxlFile& f, const std::string& out_path, const PackSettings& settings) {
  if (settings.bits < kVxlzMinBits || settings.bits > kVxlzMaxBits)
    throw Error(ErrorKind::Usage, "", std::nullopt, "quantisation bits must be 11..16");
  if (settings.chunk_points < 1 || settings.chunk_points > kVxlzMaxChunkPoints)
    throw Error(ErrorKind::Usage, "", std::nullopt, "chunk points must be 1..2^31-1");
  const unsigned threads = resolve_threads(settings.threads);
  const MetaSection& m = f.meta();
  if (m.order_set == static_cast<std::uint32_t>(OrderSet::Random))
    fail_unsupported(f.path(),
                     "per-voxel random order sets (.vxl VDIR) cannot be packed by package format 2.0; "
                     "convert with --orders axis or axis+diag");
  const VoxlineIndex index = index_voxlines(f);
  const std::uint64_t n = index.first_point.back();

  // Quantisation grid (spec §3, §5.1).
  VxlzContent c;
  c.pack = plan_quantisation(f, settings, n, threads);
  const PackSection& pack = c.pack;
  // The exact part (spec §4).
  c.meta = m;
  c.directions.assign(f.directions().begin(), f.directions().end());
  c.voxel_coords = encode_voxel_coords(f.voxels());
  c.streamline_voxlines = encode_streamline_voxlines(f.streamline_first_voxline());
  c.voxline_voxels = encode_voxline_voxels(f.voxlines(), f.voxels());
  c.voxline_counts = encode_voxline_counts(f.voxlines());
  if (f.find_section(section_id("PROV"))) {
    // Nesting that unpack would refuse is refused here, not packed into a file that cannot be unpacked.
    (void)parse_json(f.provenance_json(), f.path(), f.provenance_offset(), "PROV");
    c.provenance = std::string(f.provenance_json());
  }
  if (f.find_section(section_id("GRPS"))) c.groups = encode_group_stream(f.groups());
  // Values per group travel as the .vxl's GDAT payload, re-encoded from what open() checked (spec §4.8).
  if (!f.group_values().empty()) c.group_values = encode_group_values(f.group_values());

  // The exact part is deflated on a thread of its own while the positions are encoded (unless one thread
  // was asked for): the voxline voxels take seconds to deflate on a large tractogram, and would otherwise
  // run alone at the end.
  DeflatedTables tables;
  parallel_invoke(
      threads > 1,
      [&] {
        tables = deflate_tables(c, 1);
        if (!f.vertex_values().empty()) c.point_values = encode_value_section(shipped_point_values(f, index), 1);
        if (!f.streamline_values().empty())
          c.streamline_values = encode_value_section(streamline_values(f.streamline_values()), 1);
      },
      [&] { encode_positions(f, index, threads, c); });

  PackSummary s;
  s.bytes = write_vxlz(out_path, c, tables);
  s.streamlines = m.streamline_count;
  s.points = m.point_count;
  s.shipped_points = n;
  s.pack = pack;
  s.point_value_sets = f.vertex_values().size();
  s.streamline_value_sets = f.streamline_values().size();
  return s;
}

}  // namespace vxl
