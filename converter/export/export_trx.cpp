#include "converter/export/export_trx.h"

#include <cmath>
#include <limits>
#include <optional>
#include <unordered_set>
#include <vector>

#include <zip.h>
#include <nlohmann/json.hpp>

#include "converter/export/export_values.h"
#include "format/base/error.h"
#include "format/base/json_limits.h"
#include "format/base/output_path.h"
#include "format/vxl_streamlines.h"

namespace vxl {
namespace {

using Matrix = std::array<std::array<double, 4>, 4>;

std::optional<std::array<std::int64_t, 3>> dimensions_from(const nlohmann::json& j) {
  if (!j.is_array() || j.size() != 3) return std::nullopt;
  std::array<std::int64_t, 3> d{};
  for (int c = 0; c < 3; ++c) {
    if (!j[c].is_number_integer() || j[c].get<std::int64_t>() < 1) return std::nullopt;
    d[c] = j[c].get<std::int64_t>();
  }
  return d;
}

// A 4 x 4 array of finite numbers, or 16 numbers row-major (how the provenance stores vox_to_ras).
std::optional<Matrix> matrix_from(const nlohmann::json& j) {
  if (!j.is_array()) return std::nullopt;
  const bool flat = j.size() == 16;
  if (!flat && j.size() != 4) return std::nullopt;
  Matrix m{};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      const nlohmann::json& v =
          flat ? j[4 * r + c] : (j[r].is_array() && j[r].size() == 4 ? j[r][c] : nlohmann::json());
      if (!v.is_number() || !std::isfinite(v.get<double>())) return std::nullopt;
      m[r][c] = v.get<double>();
    }
  return m;
}

class ZipWriter {
 public:
  explicit ZipWriter(const std::string& path) : path_(path) {
    int code = 0;
    // libzip writes a temporary file and renames it over the path: the output rule applies.
    zip_ = zip_open(output_target(path).c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
    if (!zip_) {
      zip_error_t e;
      zip_error_init_with_code(&e, code);
      const std::string what = zip_error_strerror(&e);
      zip_error_fini(&e);
      throw Error(ErrorKind::Output, path_, std::nullopt, "cannot create the archive: " + what);
    }
  }
  ~ZipWriter() {
    if (zip_) zip_discard(zip_);  // nothing is written without close()
  }
  ZipWriter(const ZipWriter&) = delete;
  ZipWriter& operator=(const ZipWriter&) = delete;

  // `data` must stay alive until close(): libzip reads it then.
  void add_stored(const std::string& name, const void* data, std::size_t size) {
    zip_source_t* source = zip_source_buffer(zip_, data, size, 0);
    if (!source) fail("cannot add " + name);
    const zip_int64_t index = zip_file_add(zip_, name.c_str(), source, ZIP_FL_ENC_UTF_8);
    if (index < 0) {
      zip_source_free(source);
      fail("cannot add " + name);
    }
    // Stored, as the TRX specification recommends, so that readers can map the arrays in place.
    if (zip_set_file_compression(zip_, static_cast<zip_uint64_t>(index), ZIP_CM_STORE, 0) < 0)
      fail("cannot store " + name);
  }

  // Writes the archive to a temporary file beside the output and renames it into place.
  void close() {
    if (zip_close(zip_) < 0) fail("cannot write the archive");
    zip_ = nullptr;
  }

 private:
  [[noreturn]] void fail(const std::string& what) {
    throw Error(ErrorKind::Output, path_, std::nullopt, what + ": " + zip_strerror(zip_));
  }
  std::string path_;
  zip_t* zip_ = nullptr;
};

}  // namespace

TrxReference trx_reference(const VxlFile& file) {
  const nlohmann::json prov = parse_json(file.provenance_json(), file.path(), file.provenance_offset(), "PROV");
  if (prov.is_object() && prov.contains("source") && prov["source"].is_object()) {
    // PROV may hold any JSON (open() does not look into it): take each field only with the expected type.
    const nlohmann::json& src = prov["source"];
    const std::string format =
        src.contains("format") && src["format"].is_string() ? src["format"].get<std::string>() : "";
    const nlohmann::json header = src.value("header", nlohmann::json());
    std::optional<std::array<std::int64_t, 3>> dims;
    std::optional<Matrix> matrix;
    if (format == "trx" && header.is_object()) {
      dims = dimensions_from(header.value("DIMENSIONS", nlohmann::json()));
      matrix = matrix_from(header.value("VOXEL_TO_RASMM", nlohmann::json()));
    } else if (format == "trk" && header.is_object()) {
      dims = dimensions_from(header.value("dim", nlohmann::json()));
      matrix = matrix_from(src.value("vox_to_ras", nlohmann::json()));
    }
    if (dims && matrix) return {*dims, *matrix};
  }
  // The default: a 1 mm grid covering the bounds (see the header).
  TrxReference r;
  const MetaSection& m = file.meta();
  if (m.vertex_count == 0) return r;
  for (int c = 0; c < 3; ++c) {
    const double corner = std::floor(m.bounds_min[c]);
    r.voxel_to_rasmm[c][3] = corner;
    r.dimensions[c] = static_cast<std::int64_t>(std::ceil(m.bounds_max[c] - corner)) + 1;
  }
  return r;
}

void export_trx(const VxlFile& file, const std::string& out_path, const StreamlineSubset* subset) {
  const MetaSection& m = file.meta();
  const SubsetCounts counts = subset_counts(file, subset);
  std::vector<float> positions;
  positions.reserve(3 * counts.points);
  std::vector<std::uint64_t> offsets;
  offsets.reserve(counts.streamlines + 1);
  offsets.push_back(0);
  WalkCallbacks cb;
  cb.threads = 0;  // the points decoded on every core
  cb.read_points = [&](std::uint64_t s) { return in_subset(subset, s); };
  cb.streamline = [&](std::uint64_t, std::span<const float> xyz) {
    positions.insert(positions.end(), xyz.begin(), xyz.end());
    offsets.push_back(positions.size() / 3);
  };
  walk_streamlines(file, cb);

  const TrxReference ref = trx_reference(file);
  nlohmann::json header;
  header["DIMENSIONS"] = ref.dimensions;
  header["VOXEL_TO_RASMM"] = ref.voxel_to_rasmm;
  header["NB_STREAMLINES"] = counts.streamlines;
  header["NB_VERTICES"] = counts.points;
  const std::string header_text = header.dump(2);

  std::vector<StreamlineGroup> groups = file.groups();
  std::vector<std::vector<std::uint32_t>> members(groups.size());
  // Everything about the input is checked before the archive is created: a group TRX cannot hold is the
  // input's limit (exit 4), not a failure to write (exit 5).
  std::unordered_set<std::string> names;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (!usable_trx_member_name(groups[g].name, "groups/", ".uint32"))
      fail_unsupported(file.path(), "group name '" + groups[g].name.substr(0, 200) +
                                        "' cannot be a TRX member name (groups/NAME.uint32)");
    if (!names.insert(groups[g].name).second)
      fail_unsupported(file.path(),
                       "two groups are named '" + groups[g].name + "': TRX holds one groups/NAME.uint32 per name");
    if (m.streamline_count > std::numeric_limits<std::uint32_t>::max())
      fail_unsupported(file.path(), "TRX group members are uint32: more than 2^32 - 1 streamlines cannot be grouped");
    if (subset) groups[g].members = subset->renumber(groups[g].members);
    members[g].assign(groups[g].members.begin(), groups[g].members.end());
  }

  // dpg/<group>/<name>[.<n>].<dtype>: each row's bytes as the source had them (spec §5.13).
  const std::vector<GroupValues>& rows = file.group_values();
  std::vector<std::string> row_members;
  for (const GroupValues& v : rows) {
    row_members.push_back("dpg/" + groups[v.group].name + "/" + group_value_file_name(v));
    if (row_members.back().size() > 0xFFFF)
      fail_unsupported(file.path(), "the dpg member for '" + v.name.substr(0, 200) + "' of group '" +
                                        groups[v.group].name.substr(0, 200) + "' is longer than a zip name can be");
  }

  // dpv / dps from the value sets (export_values.h); built before the archive is opened.
  const std::vector<TrxValueMember> values = trx_value_members(file, subset);

  ZipWriter zip(out_path);
  zip.add_stored("header.json", header_text.data(), header_text.size());
  zip.add_stored("positions.3.float32", positions.data(), positions.size() * sizeof(float));
  zip.add_stored("offsets.uint64", offsets.data(), offsets.size() * sizeof(std::uint64_t));
  for (std::size_t g = 0; g < groups.size(); ++g)
    zip.add_stored("groups/" + groups[g].name + ".uint32", members[g].data(),
                   members[g].size() * sizeof(std::uint32_t));
  for (const TrxValueMember& v : values) zip.add_stored(v.name, v.data.data(), v.data.size() * sizeof(float));
  for (std::size_t r = 0; r < rows.size(); ++r)
    zip.add_stored(row_members[r], rows[r].bytes.data(), rows[r].bytes.size());
  zip.close();
}

}  // namespace vxl
