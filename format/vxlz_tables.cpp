#include "format/vxlz_tables.h"

#include <algorithm>
#include <string>

#include "format/base/error.h"
#include "format/base/utf8_check.h"

namespace vxl {
namespace {

// Every value takes at least one byte: a count the stream cannot hold is refused before anything is
// allocated for it.
void expect_room(const VarintReader& in, std::span<const std::uint8_t> stream, std::uint64_t values,
                 std::uint64_t count) {
  if (count > stream.size() / values)
    in.fail("stream of " + std::to_string(stream.size()) + " bytes cannot hold " + std::to_string(count) + " entries");
}

}  // namespace

std::vector<std::uint8_t> encode_voxel_coords(std::span<const VoxelEntry> voxels) {
  VarintWriter out;
  std::int64_t previous[3] = {0, 0, 0};
  for (const VoxelEntry& v : voxels)
    for (int c = 0; c < 3; ++c) {
      out.put_signed(v.coord[c] - previous[c]);
      previous[c] = v.coord[c];
    }
  return std::move(out.bytes());
}

std::vector<std::uint8_t> encode_streamline_voxlines(std::span<const std::uint64_t> strm) {
  VarintWriter out;
  for (std::size_t j = 0; j + 1 < strm.size(); ++j) out.put(strm[j + 1] - strm[j]);
  return std::move(out.bytes());
}

// VXLV (spec §4.4): a step to one of the 27 voxels around the previous voxline's (itself included) is
// one code 1..27; anything else is 0 followed by the index difference.
constexpr std::uint64_t kFarVoxel = 0;
int neighbour_code(const std::int32_t (&from)[3], const std::int32_t (&to)[3]) {
  int code = 0;
  for (int c = 2; c >= 0; --c) {
    const std::int64_t d = std::int64_t(to[c]) - from[c];
    if (d < -1 || d > 1) return 0;
    code = 3 * code + int(d + 1);
  }
  return 1 + code;
}

std::vector<std::uint8_t> encode_voxline_voxels(std::span<const VoxlineEntry> voxlines,
                                                std::span<const VoxelEntry> voxels) {
  VarintWriter out;
  std::uint32_t previous = 0;
  for (const VoxlineEntry& e : voxlines) {
    const int code = voxels.empty() ? 0 : neighbour_code(voxels[previous].coord, voxels[e.voxel].coord);
    out.put(static_cast<std::uint64_t>(code));
    if (code == 0) out.put_signed(std::int64_t(e.voxel) - std::int64_t(previous));
    previous = e.voxel;
  }
  return std::move(out.bytes());
}

std::vector<std::uint8_t> encode_voxline_counts(std::span<const VoxlineEntry> voxlines) {
  VarintWriter out;
  for (const VoxlineEntry& e : voxlines)
    out.put(std::uint64_t(e.count_flags & kVoxlineCountMask) << 1 | (e.count_flags >> 31));
  return std::move(out.bytes());
}

std::vector<std::uint8_t> encode_group_stream(std::span<const StreamlineGroup> groups) {
  VarintWriter out;
  out.put(groups.size());
  for (const StreamlineGroup& g : groups) {
    out.put(g.name.size());
    out.put_bytes(g.name.data(), g.name.size());
    out.put(g.members.size());
    for (std::size_t i = 0; i < g.members.size(); ++i)
      out.put(i == 0 ? g.members[0] : g.members[i] - g.members[i - 1] - 1);
  }
  return std::move(out.bytes());
}

std::vector<std::array<std::int32_t, 3>> decode_voxel_coords(std::span<const std::uint8_t> stream, std::uint32_t count,
                                                             const std::int32_t grid_dims[3],
                                                             const StreamContext& context) {
  VarintReader in(stream, context);
  expect_room(in, stream, 3, count);
  std::vector<std::array<std::int32_t, 3>> coords(count);
  std::int64_t previous[3] = {0, 0, 0};
  std::int32_t lowest[3] = {INT32_MAX, INT32_MAX, INT32_MAX}, highest[3] = {-1, -1, -1};
  for (std::uint32_t i = 0; i < count; ++i) {
    for (int c = 0; c < 3; ++c) {
      const std::int64_t delta = in.get_signed();
      // |delta| and the previous coordinate are both below 2^63 / 2 only if sane: check before adding.
      if (delta < -std::int64_t(grid_dims[c]) || delta > std::int64_t(grid_dims[c]))
        in.fail("voxel " + std::to_string(i) + " coordinate outside the grid");
      const std::int64_t v = previous[c] + delta;
      if (v < 0 || v >= grid_dims[c]) in.fail("voxel " + std::to_string(i) + " coordinate outside the grid");
      coords[i][c] = static_cast<std::int32_t>(v);
      previous[c] = v;
      lowest[c] = std::min(lowest[c], coords[i][c]), highest[c] = std::max(highest[c], coords[i][c]);
    }
    if (i > 0) {
      const auto& u = coords[i - 1];
      const auto& v = coords[i];
      if (!(std::array{u[2], u[1], u[0]} < std::array{v[2], v[1], v[0]}))
        in.fail("voxel coordinates not strictly increasing in (z, y, x) at voxel " + std::to_string(i));
    }
  }
  in.expect_end();
  // The grid as large as the points make it (.vxl spec §6.1): a grid larger than its voxels unpacks to a file verify
  // refuses.
  for (int c = 0; c < 3 && count > 0; ++c)
    if (lowest[c] != 0 || highest[c] != grid_dims[c] - 1)
      in.fail("voxel coordinates on " + std::string(1, "xyz"[c]) + " run from " + std::to_string(lowest[c]) + " to " +
              std::to_string(highest[c]) + ", not from 0 to grid_dims - 1 = " + std::to_string(grid_dims[c] - 1));
  return coords;
}

std::vector<std::uint64_t> decode_streamline_voxlines(std::span<const std::uint8_t> stream,
                                                      std::uint64_t streamline_count, std::uint64_t voxline_count,
                                                      const StreamContext& context) {
  VarintReader in(stream, context);
  expect_room(in, stream, 1, streamline_count);
  std::vector<std::uint64_t> strm(streamline_count + 1);
  strm[0] = 0;
  for (std::uint64_t j = 0; j < streamline_count; ++j) {
    const std::uint64_t n = in.get();
    if (n > voxline_count - strm[j]) in.fail("streamlines hold more voxlines than META's voxline count");
    strm[j + 1] = strm[j] + n;
  }
  in.expect_end();
  if (strm[streamline_count] != voxline_count) in.fail("streamlines hold fewer voxlines than META's voxline count");
  return strm;
}

void decode_voxline_voxels(std::span<const std::uint8_t> stream, std::span<const std::array<std::int32_t, 3>> coords,
                           std::span<VoxlineEntry> voxlines, const StreamContext& context) {
  VarintReader in(stream, context);
  expect_room(in, stream, 1, voxlines.size());
  const std::int64_t voxel_count = static_cast<std::int64_t>(coords.size());
  // Neighbour codes resolve through a cache per (voxel, code), filled by binary search on first use:
  // a streamline moves between few pairs of voxels, so searches are rare.
  constexpr std::uint32_t kUnknown = 0xFFFFFFFFu;
  std::vector<std::uint32_t> neighbour(coords.size() * 27, kUnknown);
  auto zyx = [](const std::array<std::int32_t, 3>& c) { return std::array<std::int32_t, 3>{c[2], c[1], c[0]}; };
  std::int64_t voxel = 0;
  for (std::size_t j = 0; j < voxlines.size(); ++j) {
    const std::uint64_t code = in.get();
    if (code == kFarVoxel) {
      const std::int64_t delta = in.get_signed();
      if (delta < -voxel_count || delta >= voxel_count || voxel + delta < 0 || voxel + delta >= voxel_count)
        in.fail("voxline " + std::to_string(j) + " refers to a voxel past the table");
      voxel += delta;
    } else {
      if (code > 27 || voxel_count == 0) in.fail("voxline " + std::to_string(j) + " has an unknown voxel code");
      std::uint32_t& cached = neighbour[std::size_t(voxel) * 27 + (code - 1)];
      if (cached == kUnknown) {
        std::array<std::int32_t, 3> target = coords[voxel];
        for (int c = 0, rest = int(code - 1); c < 3; ++c, rest /= 3) target[c] += rest % 3 - 1;
        auto it = std::lower_bound(coords.begin(), coords.end(), target,
                                   [&](const auto& a, const auto& b) { return zyx(a) < zyx(b); });
        if (it == coords.end() || *it != target)
          in.fail("voxline " + std::to_string(j) + " steps to a voxel that is not in the table");
        cached = static_cast<std::uint32_t>(it - coords.begin());
      }
      voxel = cached;
    }
    voxlines[j].voxel = static_cast<std::uint32_t>(voxel);
  }
  in.expect_end();
}

void decode_voxline_counts(std::span<const std::uint8_t> stream, std::span<VoxlineEntry> voxlines,
                           const StreamContext& context) {
  VarintReader in(stream, context);
  expect_room(in, stream, 1, voxlines.size());
  for (std::size_t j = 0; j < voxlines.size(); ++j) {
    const std::uint64_t c = in.get();
    const std::uint64_t own = c >> 1;
    if (own < 1 || own > kVoxlineCountMask)
      in.fail("voxline " + std::to_string(j) + " own point count must be 1..2^31-1");
    voxlines[j].count_flags = static_cast<std::uint32_t>(own) | (c & 1 ? kVoxlineSyntheticFirst : 0);
  }
  in.expect_end();
}

std::vector<StreamlineGroup> decode_group_stream(std::span<const std::uint8_t> stream, std::uint64_t streamline_count,
                                                 const StreamContext& context) {
  VarintReader in(stream, context);
  const std::uint64_t group_count = in.get();
  if (group_count > 0xFFFFFFFFu) in.fail("more than 2^32-1 groups");
  expect_room(in, stream, 2, group_count);
  std::vector<StreamlineGroup> groups;
  for (std::uint64_t g = 0; g < group_count; ++g) {
    StreamlineGroup gc;
    std::span<const std::uint8_t> name = in.get_bytes(in.get());
    gc.name.assign(name.begin(), name.end());
    if (gc.name.find('\0') != std::string::npos) in.fail("group name contains a NUL byte");
    if (!is_valid_utf8(gc.name)) in.fail("group name is not valid UTF-8");
    const std::uint64_t members = in.get();
    expect_room(in, stream, 1, members);
    gc.members.reserve(members);
    std::uint64_t next_allowed = 0;  // members strictly increase: each is at least the previous + 1
    for (std::uint64_t i = 0; i < members; ++i) {
      const std::uint64_t gap = in.get();
      if (gap >= streamline_count || next_allowed > streamline_count - 1 - gap)
        in.fail("group '" + gc.name + "' member past the streamline count");
      gc.members.push_back(next_allowed + gap);
      next_allowed = gc.members.back() + 1;
    }
    groups.push_back(std::move(gc));
  }
  in.expect_end();
  return groups;
}

}  // namespace vxl
