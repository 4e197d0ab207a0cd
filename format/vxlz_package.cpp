#include "format/vxlz_package.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include <sys/stat.h>
#include <unistd.h>

#include "format/base/atomic_output.h"
#include "format/base/checksum.h"
#include "format/base/error.h"
#include "format/base/parallel.h"
#include "format/base/regular_file.h"
#include "format/vxl_file.h"
#include "format/vxl_levels.h"

namespace vxl {
namespace {

template <typename T>
std::vector<std::uint8_t> bytes_of(const T& value) {
  const auto* b = reinterpret_cast<const std::uint8_t*>(&value);
  return {b, b + sizeof value};
}

// The sections every package has (spec §2.2), and the optional ones this reader knows.
constexpr std::uint32_t kRequired[] = {section_id("PACK"), section_id("META"), section_id("DIRS"),
                                       section_id("VOXC"), section_id("STRL"), section_id("VXLV"),
                                       section_id("VXLC"), section_id("CHNK"), section_id("POSD")};
constexpr std::uint32_t kOptional[] = {section_id("PROV"), section_id("GRPS"), section_id("PVAL"),
                                       section_id("SVAL"), section_id("GDAT"), section_id("CHKS")};

}  // namespace

DeflatedTables deflate_tables(const VxlzContent& c, unsigned threads) {
  DeflatedTables d;
  if (c.provenance) d.provenance.emplace();
  if (c.groups) d.groups.emplace();
  if (c.group_values) d.group_values.emplace();
  struct Job {
    std::span<const std::uint8_t> raw;
    DeflateMode mode;
    std::vector<std::uint8_t>* out;
  };
  // Largest first, side by side. Counts and streamline lengths are numbers that seldom repeat in
  // sequence: entropy coding alone makes them smaller than string matching does (VXLC 4.00 against 4.32
  // MB, STRL 0.49 against 0.56 MB on the 1M set, similar on real data), in a tenth of the time. Voxel
  // steps repeat along streamlines, and string matching gains 11 % there.
  std::vector<Job> jobs = {{c.voxline_voxels, DeflateMode::Matching, &d.voxline_voxels},
                           {c.voxline_counts, DeflateMode::HuffmanOnly, &d.voxline_counts},
                           {c.streamline_voxlines, DeflateMode::HuffmanOnly, &d.streamline_voxlines},
                           {c.voxel_coords, DeflateMode::Matching, &d.voxel_coords}};
  if (c.provenance)
    jobs.push_back({{reinterpret_cast<const std::uint8_t*>(c.provenance->data()), c.provenance->size()},
                    DeflateMode::Matching,
                    &*d.provenance});
  if (c.groups) jobs.push_back({*c.groups, DeflateMode::Matching, &*d.groups});
  if (c.group_values) jobs.push_back({*c.group_values, DeflateMode::Matching, &*d.group_values});
  parallel_for(jobs.size(), threads,
               [&](std::uint64_t i, unsigned) { *jobs[i].out = deflate_section(jobs[i].raw, jobs[i].mode); });
  return d;
}

std::uint64_t write_vxlz(const std::string& path, const VxlzContent& c, unsigned threads) {
  return write_vxlz(path, c, deflate_tables(c, threads));
}

std::uint64_t write_vxlz(const std::string& path, const VxlzContent& c, const DeflatedTables& d) {
  struct Section {
    const char* id;
    bool required;
    std::span<const std::uint8_t> payload;  // empty for POSD, written chunk by chunk
  };
  PackSection pack = c.pack;
  std::memset(pack.reserved, 0, sizeof pack.reserved);
  MetaSection meta = c.meta;
  meta.position_encoding = 0;  // the package's positions are its own; the unpacker chooses the .vxl's
  meta.level_count = 0;        // likewise its levels
  std::memset(meta.reserved, 0, sizeof meta.reserved);
  const std::vector<std::uint8_t> pack_bytes = bytes_of(pack), meta_bytes = bytes_of(meta);
  // POSD is the chunks' buffers back to back: written from them, never gathered into one copy.
  std::vector<std::uint8_t> chunk_sizes, chunk_checksums;
  std::uint64_t posd_size = 0;
  Xxh3_64Stream posd_checksum;
  auto append_u64 = [](std::vector<std::uint8_t>& to, std::uint64_t n) {
    to.insert(to.end(), reinterpret_cast<const std::uint8_t*>(&n), reinterpret_cast<const std::uint8_t*>(&n) + 8);
  };
  for (const EncodedChunk& chunk : c.chunks) {
    Xxh3_64Stream chunk_checksum;
    for (const std::vector<std::uint8_t>* buffer : {&chunk.symbols, &chunk.escapes}) {
      append_u64(chunk_sizes, buffer->size());
      posd_size += buffer->size();
      posd_checksum.update(buffer->data(), buffer->size());
      chunk_checksum.update(buffer->data(), buffer->size());
    }
    append_u64(chunk_checksums, chunk_checksum.digest());
  }
  // With the level order only (spec §2.2): there a prefix is shown before the whole has arrived.
  const bool level_order = c.pack.predictor == kVxlzPredictorLinearLevelOrder;

  std::vector<Section> sections;
  sections.push_back({"PACK", true, pack_bytes});
  sections.push_back({"META", true, meta_bytes});
  sections.push_back(
      {"DIRS",
       true,
       {reinterpret_cast<const std::uint8_t*>(c.directions.data()), c.directions.size() * sizeof(DirectionEntry)}});
  sections.push_back({"VOXC", true, d.voxel_coords});
  sections.push_back({"STRL", true, d.streamline_voxlines});
  sections.push_back({"VXLV", true, d.voxline_voxels});
  sections.push_back({"VXLC", true, d.voxline_counts});
  if (d.provenance) sections.push_back({"PROV", false, *d.provenance});
  if (d.groups) sections.push_back({"GRPS", false, *d.groups});
  // Optional (spec §4.7): a 2.0 reader skips them and still gets every streamline, without the values.
  if (c.point_values) sections.push_back({"PVAL", false, *c.point_values});
  if (c.streamline_values) sections.push_back({"SVAL", false, *c.streamline_values});
  // Optional (spec §4.8): a reader that skips it loses the rows of values per group only.
  if (d.group_values) sections.push_back({"GDAT", false, *d.group_values});
  sections.push_back({"CHNK", true, chunk_sizes});
  // Optional: a reader that skips it checks the positions as a whole, once every chunk is in.
  if (level_order) sections.push_back({"CHKS", false, chunk_checksums});
  sections.push_back({"POSD", true, {}});

  // Header, table, then the payloads back to back (spec §2).
  const std::uint64_t table_end = sizeof(FileHeader) + sections.size() * sizeof(SectionEntry);
  std::vector<SectionEntry> table;
  std::uint64_t position = table_end;
  for (const Section& s : sections) {
    const bool posd = std::strcmp(s.id, "POSD") == 0;
    SectionEntry e{};
    std::memcpy(e.id, s.id, 4);
    e.flags = s.required ? kSectionRequired : 0;
    e.offset = position;
    e.size = posd ? posd_size : s.payload.size();
    e.checksum = posd ? posd_checksum.digest() : xxh3_64(s.payload.data(), s.payload.size());
    table.push_back(e);
    position += e.size;
  }
  FileHeader h{};
  std::memcpy(h.magic, kVxlzMagic.data(), 8);
  h.version_major = kVxlzVersionMajor;
  h.version_minor = level_order                             ? kVxlzVersionMinorChunkChecksums
                    : c.group_values                        ? kVxlzVersionMinorGroupValues
                    : c.point_values || c.streamline_values ? kVxlzVersionMinor
                                                            : 0;
  h.header_size = sizeof(FileHeader);
  h.file_size = position;
  h.section_table_offset = sizeof(FileHeader);
  h.section_count = static_cast<std::uint32_t>(sections.size());
  std::vector<std::uint8_t> head(table_end);
  std::memcpy(head.data(), &h, sizeof h);
  std::memcpy(head.data() + sizeof h, table.data(), table.size() * sizeof(SectionEntry));
  h.header_checksum = xxh3_64(head.data(), head.size());
  std::memcpy(head.data(), &h, sizeof h);

  AtomicOutputFile out(path);
  out.write(head.data(), head.size());
  for (const Section& s : sections) out.write(s.payload.data(), s.payload.size());
  for (const EncodedChunk& chunk : c.chunks) {
    out.write(chunk.symbols.data(), chunk.symbols.size());
    out.write(chunk.escapes.data(), chunk.escapes.size());
  }
  out.commit();
  return position;
}

bool starts_as_vxlz(const std::string& path) {
  struct stat st {};
  const int fd = open_regular_file(path, st);  // a FIFO is refused, not waited on
  std::array<std::uint8_t, 8> magic{};
  const ssize_t n = ::pread(fd, magic.data(), magic.size(), 0);
  ::close(fd);
  return n == ssize_t(magic.size()) && std::memcmp(magic.data(), kVxlzMagic.data(), magic.size()) == 0;
}

VxlzFile VxlzFile::open(const std::string& path) {
  VxlzFile f{MappedFile(path)};
  f.validate();
  return f;
}

VxlzFile VxlzFile::open(MappedFile file) {
  VxlzFile f{std::move(file)};
  f.validate();
  return f;
}

VxlzFile VxlzFile::open_prefix(MappedFile prefix) {
  VxlzFile f{std::move(prefix), true};
  f.validate();
  return f;
}

std::optional<std::uint64_t> VxlzFile::positions_offset(std::span<const std::uint8_t> first_bytes) {
  FileHeader h;
  if (first_bytes.size() < sizeof h) return std::nullopt;
  std::memcpy(&h, first_bytes.data(), sizeof h);
  if (h.section_count > kVxlzMaxSections) return 0;
  const std::uint64_t table_end = sizeof h + std::uint64_t(h.section_count) * sizeof(SectionEntry);
  if (first_bytes.size() < table_end) return std::nullopt;
  for (std::uint32_t i = 0; i < h.section_count; ++i) {
    SectionEntry e;
    std::memcpy(&e, first_bytes.data() + sizeof h + i * sizeof e, sizeof e);
    if (std::memcmp(e.id, "POSD", 4) == 0) return e.offset;
  }
  return 0;
}

const SectionEntry* VxlzFile::find(std::uint32_t id) const {
  for (const SectionEntry& e : sections_) {
    std::uint32_t eid;
    std::memcpy(&eid, e.id, 4);
    if (eid == id) return &e;
  }
  return nullptr;
}

// The steps of spec §8, in order; each sets what the next relies on.
void VxlzFile::validate() {
  validate_header_and_table();
  validate_checksums();
  validate_pack_and_meta();
  validate_chunks();
}

// §8 steps 1 and 2: the header, then the table; payloads follow each other from the end of the table to
// the end of the file.
void VxlzFile::validate_header_and_table() {
  const std::string& p = file_.path();
  const std::uint64_t size = file_.size();
  const std::uint8_t* base = file_.data();
  FileHeader h;
  if (size < sizeof h) fail_input(p, size, "file too short for a .vxlz header (64 bytes): truncated or not a package");
  std::memcpy(&h, base, sizeof h);
  if (std::memcmp(h.magic, kVxlzMagic.data(), 8) != 0) fail_input(p, 0, "not a .vxlz package (bad magic)");
  if (h.version_major != kVxlzVersionMajor)
    throw Error(ErrorKind::Unsupported, p, 8,
                ".vxlz major version " + std::to_string(h.version_major) + " (this reader knows " +
                    std::to_string(kVxlzVersionMajor) + " only" +
                    (h.version_major < kVxlzVersionMajor ? "; pack the .vxl again with this version)" : ")"));
  if (h.header_size != sizeof h) fail_input(p, 12, "header_size must be 64");
  if (prefix_ ? h.file_size < size : h.file_size != size)
    fail_input(p, 16,
               "file size is " + std::to_string(size) + " bytes but the header says " + std::to_string(h.file_size) +
                   " (truncated or extended package)");
  // A prefix's sections are placed in the whole package's size; all but POSD must be in the prefix.
  const std::uint64_t whole = h.file_size;
  if (h.section_table_offset != sizeof h) fail_input(p, 24, "section table must start at byte 64");
  if (h.section_count == 0 || h.section_count > kVxlzMaxSections) fail_input(p, 32, "section count must be 1..32");
  if (h.flags != 0) fail_input(p, 36, "unknown header flags");
  if (!all_zero(h.reserved, sizeof h.reserved)) fail_input(p, 48, "reserved header bytes are not zero");
  const std::uint64_t table_end = sizeof h + std::uint64_t(h.section_count) * sizeof(SectionEntry);
  if (table_end > size) fail_input(p, 64, "section table runs past the end of the file");
  {
    std::vector<std::uint8_t> head(base, base + table_end);
    std::memset(head.data() + offsetof(FileHeader, header_checksum), 0, 8);
    if (xxh3_64(head.data(), head.size()) != h.header_checksum)
      fail_input(p, 40, "header checksum mismatch (header or section table damaged)");
  }
  header_ = h;
  sections_.resize(h.section_count);
  std::memcpy(sections_.data(), base + sizeof h, sections_.size() * sizeof(SectionEntry));

  std::uint64_t expected_offset = table_end;
  for (std::size_t i = 0; i < sections_.size(); ++i) {
    const SectionEntry& e = sections_[i];
    const std::uint64_t at = sizeof h + i * sizeof(SectionEntry);
    std::uint32_t id;
    std::memcpy(&id, e.id, 4);
    const std::string name = section_name(id);
    if ((e.flags & ~kSectionRequired) != 0) fail_input(p, at + 4, "section " + name + " has unknown flags");
    if (find(id) != &e) fail_input(p, at, "section " + name + " appears twice");
    if (e.offset != expected_offset)
      fail_input(p, at + 8,
                 "section " + name + " must start at byte " + std::to_string(expected_offset) +
                     " (right after the previous one)");
    if (e.size > whole - e.offset) fail_input(p, at + 16, "section " + name + " runs past the end of the file");
    if (e.size > size - std::min(size, e.offset) && id != section_id("POSD"))
      fail_input(p, size,
                 "the package's first " + std::to_string(size) + " bytes hold part of section " + name +
                     ": opening it needs the first " + std::to_string(e.offset + e.size));
    expected_offset += e.size;
    const bool known = std::find(std::begin(kRequired), std::end(kRequired), id) != std::end(kRequired) ||
                       std::find(std::begin(kOptional), std::end(kOptional), id) != std::end(kOptional);
    if (!known && (e.flags & kSectionRequired))
      throw Error(ErrorKind::Unsupported, p, at,
                  "required section " + name + " is unknown to this reader (newer writer?)");
  }
  if (expected_offset != whole) fail_input(p, expected_offset, "bytes after the last section");
  for (std::uint32_t id : kRequired)
    if (!find(id)) fail_input(p, 64, "required section " + section_name(id) + " is missing");
}

// §8 step 3: every checksum, before anything is decoded.
void VxlzFile::validate_checksums() const {
  const std::string& p = file_.path();
  const std::uint8_t* base = file_.data();
  for (const SectionEntry& e : sections_)
    if (!(prefix_ && std::memcmp(e.id, "POSD", 4) == 0) && xxh3_64(base + e.offset, e.size) != e.checksum)
      fail_input(p, e.offset, "checksum mismatch in section " + std::string(e.id, 4) + " (damaged package)");
}

// §8 step 4: the fixed-size sections PACK, META and DIRS.
void VxlzFile::validate_pack_and_meta() {
  const std::string& p = file_.path();
  const std::uint8_t* base = file_.data();
  auto fixed = [&](const char(&id)[5], std::uint64_t expected, void* dst) {
    const SectionEntry* e = find(section_id(id));
    if (e->size != expected)
      fail_input(p, e->offset, std::string("section ") + id + " must be " + std::to_string(expected) + " bytes");
    std::memcpy(dst, base + e->offset, expected);
    return e->offset;
  };
  const std::uint64_t pack_at = fixed("PACK", sizeof pack_, &pack_);
  const PackSection& k = pack_;
  if (k.quantization_bits < kVxlzMinBits || k.quantization_bits > kVxlzMaxBits)
    fail_input(p, pack_at, "quantization bits must be 11..16");
  if (k.predictor != kVxlzPredictorLinear && k.predictor != kVxlzPredictorLinearLevelOrder)
    throw Error(ErrorKind::Unsupported, p, pack_at + 4,
                "predictor " + std::to_string(k.predictor) + " (this reader knows 1 and 2)");
  if (k.predictor == kVxlzPredictorLinearLevelOrder ? k.level_count < 2 || k.level_count > kMaxLevels
                                                    : k.level_count != 0)
    fail_input(p, pack_at + 100,
               "PACK level count " + std::to_string(k.level_count) + " (2..8 with predictor 2, else 0)");
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(k.quant_origin[c])) fail_input(p, pack_at + 8, "quantisation origin is not finite");
  if (!std::isfinite(k.quantum) || !(k.quantum > 0)) fail_input(p, pack_at + 32, "quantum must be finite and positive");
  // Every decoded coordinate must be a finite float32: the whole cube must lie within float range.
  const double cube_edge = k.quantum * double((1u << k.quantization_bits) - 1);
  for (int c = 0; c < 3; ++c)
    if (!(std::abs(k.quant_origin[c]) <= std::numeric_limits<float>::max()) ||
        !(std::abs(k.quant_origin[c] + cube_edge) <= std::numeric_limits<float>::max()))
      fail_input(p, pack_at + 8, "quantisation cube reaches beyond the float32 range");
  if (k.chunk_points < 1 || k.chunk_points > kVxlzMaxChunkPoints)
    fail_input(p, pack_at + 56, "chunk points must be 1..2^31-1");
  if (k.chunk_count != k.point_count / k.chunk_points + (k.point_count % k.chunk_points != 0))
    fail_input(p, pack_at + 64, "chunk count does not match point count / chunk points");
  if (k.joint_bits < kVxlzMinJointBits || k.joint_bits > kVxlzMaxJointBits)
    fail_input(p, pack_at + 96, "joint symbol bits must be 1..5");
  if (!all_zero(k.reserved, sizeof k.reserved)) fail_input(p, pack_at + 104, "PACK reserved bytes are not zero");

  const std::uint64_t meta_at = fixed("META", sizeof meta_, &meta_);
  const MetaSection& m = meta_;
  // The package's copy of META carries no position encoding and no levels: its positions are its own, and
  // the unpacker chooses the levels of the .vxl it writes (spec §5).
  if (m.position_encoding != 0 || m.level_count != 0 || !all_zero(m.reserved, sizeof m.reserved))
    fail_input(p, meta_at + 152, "META reserved bytes are not zero");
  if (!std::isfinite(m.voxel_size) || !(m.voxel_size > 0))
    fail_input(p, meta_at + 56, "voxel size must be finite and positive");
  if (m.stored_order_count < 1 || m.stored_order_count > kVxlMaxStoredOrders)
    fail_input(p, meta_at + 52, "stored order count must be 1..64");
  check_order_set(m, p, meta_at);
  if (m.voxel_count > 0x7FFFFFFFu) fail_input(p, meta_at + 48, "voxel count exceeds 2^31-1");
  for (int c = 0; c < 3; ++c) {
    if (m.grid_dims[c] < 0) fail_input(p, meta_at + 88, "negative grid dimension");
    if (!std::isfinite(m.grid_origin[c])) fail_input(p, meta_at + 64, "grid origin is not finite");
  }
  // Bounds, origin, voxel size and grid dimensions must agree as in a .vxl (spec §7): the unpacker recomputes
  // the bounds from the decoded positions, but the grid it writes voxels into is this one.
  check_grid_geometry(m, p, meta_at);
  if (m.point_count > ~std::uint64_t(0) - m.synthetic_point_count ||
      m.point_count + m.synthetic_point_count != k.point_count)
    fail_input(p, pack_at + 48, "shipped point count must be META's point count plus its synthetic point count");

  directions_.resize(m.stored_order_count);
  const std::uint64_t dirs_at =
      fixed("DIRS", std::uint64_t(m.stored_order_count) * sizeof(DirectionEntry), directions_.data());
  for (std::size_t i = 0; i < directions_.size(); ++i) {
    const DirectionEntry& d = directions_[i];
    const double len =
        std::sqrt(double(d.xyz[0]) * d.xyz[0] + double(d.xyz[1]) * d.xyz[1] + double(d.xyz[2]) * d.xyz[2]);
    if (d.reserved != 0 || !(std::abs(len - 1.0) < 1e-5))
      fail_input(p, dirs_at + 16 * i, "direction is not a unit vector");
  }
}

// The chunk table: two sizes per chunk, adding up to POSD.
void VxlzFile::validate_chunks() {
  const std::string& p = file_.path();
  const std::uint8_t* base = file_.data();
  const PackSection& k = pack_;
  const SectionEntry* chnk = find(section_id("CHNK"));
  const SectionEntry* posd = find(section_id("POSD"));
  if (chnk->size / 16 != k.chunk_count || chnk->size % 16 != 0)
    fail_input(p, chnk->offset,
               "CHNK must hold two 8-byte sizes per chunk (" + std::to_string(k.chunk_count) + " chunks)");
  chunk_offsets_.assign(1, 0);
  for (std::uint64_t i = 0; i < 2 * k.chunk_count; ++i) {
    std::uint64_t n;
    std::memcpy(&n, base + chnk->offset + 8 * i, 8);
    if (n > posd->size - chunk_offsets_.back()) fail_input(p, chnk->offset + 8 * i, "chunk runs past the end of POSD");
    chunk_offsets_.push_back(chunk_offsets_.back() + n);
  }
  if (chunk_offsets_.back() != posd->size) fail_input(p, chnk->offset, "chunk sizes do not add up to the POSD size");
  posd_offset_ = posd->offset;
  validate_chunk_checksums();
}

// CHKS, where the package has it: a checksum per chunk, each present chunk checked (a prefix's too, which POSD's
// checksum cannot be until the whole has arrived).
void VxlzFile::validate_chunk_checksums() const {
  const SectionEntry* chks = find(section_id("CHKS"));
  if (!chks) return;
  const std::string& p = file_.path();
  if (chks->size != 8 * pack_.chunk_count)
    fail_input(p, chks->offset,
               "CHKS must hold one 8-byte checksum per chunk (" + std::to_string(pack_.chunk_count) + " chunks)");
  for (std::uint64_t i = 0, present = chunks_present(); i < present; ++i) {
    std::uint64_t expected;
    std::memcpy(&expected, file_.data() + chks->offset + 8 * i, 8);
    const std::uint64_t begin = posd_offset_ + chunk_offsets_[2 * i], end = posd_offset_ + chunk_offsets_[2 * i + 2];
    if (xxh3_64(file_.data() + begin, end - begin) != expected)
      fail_input(p, begin, "checksum mismatch in position chunk " + std::to_string(i) + " (CHKS; damaged package)");
  }
}

std::vector<std::uint8_t> VxlzFile::inflate(std::uint32_t id) const {
  const SectionEntry* e = find(id);
  if (!e) return {};
  return inflate_section(payload(*e), context(id));
}

StreamContext VxlzFile::context(std::uint32_t id) const {
  const SectionEntry* e = find(id);
  return {file_.path(), section_name(id), e ? e->offset : 0};
}

std::uint64_t VxlzFile::chunks_present() const {
  const std::uint64_t n = chunk_count();
  if (!prefix_) return n;
  std::uint64_t present = 0;
  while (present < n && posd_offset_ + chunk_offsets_[2 * present + 2] <= file_.size()) ++present;
  return present;
}

ChunkBytes VxlzFile::chunk(std::uint64_t i) const {
  const std::uint64_t* o = chunk_offsets_.data() + 2 * i;
  if (posd_offset_ + o[2] > file_.size())
    fail_input(file_.path(), posd_offset_ + o[0], "position chunk " + std::to_string(i) + " has not arrived");
  ChunkBytes c;
  c.symbols = file_.bytes().subspan(posd_offset_ + o[0], o[1] - o[0]);
  c.escapes = file_.bytes().subspan(posd_offset_ + o[1], o[2] - o[1]);
  c.symbols_offset = posd_offset_ + o[0];
  c.escapes_offset = posd_offset_ + o[1];
  return c;
}

std::uint64_t VxlzFile::chunk_point_count(std::uint64_t i) const {
  return std::min(pack_.chunk_points, pack_.point_count - i * pack_.chunk_points);
}

}  // namespace vxl
