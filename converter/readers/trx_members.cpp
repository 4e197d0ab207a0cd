#include "converter/readers/trx_members.h"

#include <filesystem>

#include <zip.h>

#include "format/base/error.h"

namespace vxl::trx {
namespace {

class ZipMembers : public Members {
 public:
  // `bytes` must outlive this object (it is the caller's mapping of the archive).
  ZipMembers(const std::string& path, std::span<const std::uint8_t> bytes) : path_(path) {
    zip_error_t error;
    zip_error_init(&error);
    zip_source_t* src = zip_source_buffer_create(bytes.data(), bytes.size(), 0, &error);
    if (src == nullptr) fail(error);
    zip_t* archive = zip_open_from_source(src, ZIP_RDONLY, &error);
    if (archive == nullptr) {
      zip_source_free(src);
      fail(error);
    }
    zip_error_fini(&error);
    archive_.reset(archive);
    const zip_int64_t n = zip_get_num_entries(archive, 0);
    for (zip_int64_t i = 0; i < n; ++i) {
      // libzip hands out names as UTF-8 (it converts legacy CP437 names).
      const char* name = zip_get_name(archive, static_cast<zip_uint64_t>(i), 0);
      if (name == nullptr) continue;
      std::string s = name;
      if (s.empty() || s.back() == '/') continue;  // directory entries carry no data
      if (!names_.emplace(s, static_cast<std::uint64_t>(i)).second)
        fail_input(path_, std::nullopt, "member " + s + " appears twice in the zip archive");
    }
  }
  std::uint64_t declared_size(const std::string& name) const override { return stat(name).size; }
  Blob read(const std::string& name, std::uint64_t max_bytes, const std::string& why) const override {
    zip_t* archive = archive_.get();
    const zip_stat_t st = stat(name);
    if (st.size > max_bytes)
      fail_input(path_, std::nullopt,
                 name + ": its zip entry declares " + std::to_string(st.size) + " bytes, more than the " +
                     std::to_string(max_bytes) + " " + why);
    // What the compressed bytes can inflate to at most: deflate's best ratio is 1032:1, stored is 1:1.
    if ((st.valid & ZIP_STAT_COMP_SIZE) && (st.valid & ZIP_STAT_COMP_METHOD)) {
      const zip_uint64_t most = st.comp_method == ZIP_CM_STORE     ? st.comp_size
                                : st.comp_method == ZIP_CM_DEFLATE ? st.comp_size * 1032 + 1024
                                                                   : ~zip_uint64_t{0};
      if (st.size > most)
        fail_input(path_, std::nullopt,
                   name + ": its zip entry declares " + std::to_string(st.size) + " bytes, more than its " +
                       std::to_string(st.comp_size) + " compressed bytes can hold");
    }
    zip_file_t* f = zip_fopen_index(archive, names_.at(name), 0);
    if (f == nullptr) fail_input(path_, std::nullopt, name + ": cannot open the zip entry: " + zip_strerror(archive));
    // Bounded above: the whole declared size is known to be justified, so it is allocated at once. One byte
    // beyond it is asked for to catch an entry that inflates to more than it declares.
    std::vector<std::uint8_t> out(static_cast<std::size_t>(st.size) + 1);
    std::uint64_t have = 0;
    while (have < out.size()) {
      const zip_int64_t got = zip_fread(f, out.data() + have, out.size() - have);
      if (got < 0) {
        std::string msg = zip_file_strerror(f);
        zip_fclose(f);
        fail_input(path_, std::nullopt, name + ": corrupt zip entry: " + msg);
      }
      if (got == 0) break;
      have += static_cast<std::uint64_t>(got);
    }
    zip_fclose(f);
    if (have > st.size)
      fail_input(path_, std::nullopt,
                 name + ": zip entry inflates to more than the " + std::to_string(st.size) +
                     " bytes its directory entry declares");
    out.resize(have);
    if (out.size() != st.size)
      fail_input(path_, std::nullopt,
                 name + ": zip entry holds " + std::to_string(out.size()) + " bytes but its directory entry says " +
                     std::to_string(st.size));
    return Blob(std::move(out));
  }

 private:
  zip_stat_t stat(const std::string& name) const {
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(archive_.get(), names_.at(name), 0, &st) != 0 || (st.valid & ZIP_STAT_SIZE) == 0)
      fail_input(path_, std::nullopt, name + ": cannot read the zip entry: " + zip_strerror(archive_.get()));
    return st;
  }

  [[noreturn]] void fail(zip_error_t& error) {
    std::string msg = zip_error_strerror(&error);
    zip_error_fini(&error);
    fail_input(path_, std::nullopt, "not a readable TRX zip archive: " + msg);
  }

  struct Discard {
    void operator()(zip_t* z) const { zip_discard(z); }
  };
  std::string path_;
  std::unique_ptr<zip_t, Discard> archive_;
};

class DirMembers : public Members {
 public:
  explicit DirMembers(const std::string& path) : root_(path) {
    std::error_code ec;
    std::filesystem::recursive_directory_iterator it(root_, ec), end;
    if (ec) fail_input(path, std::nullopt, "cannot list the TRX directory: " + ec.message());
    for (; it != end; it.increment(ec)) {
      if (ec) fail_input(path, std::nullopt, "cannot list the TRX directory: " + ec.message());
      if (!it->is_regular_file()) continue;
      names_.emplace(std::filesystem::relative(it->path(), root_).generic_string(), 0);
    }
    if (ec) fail_input(path, std::nullopt, "cannot list the TRX directory: " + ec.message());
  }
  std::uint64_t declared_size(const std::string& name) const override {
    std::error_code ec;
    const std::uint64_t size = std::filesystem::file_size(root_ / name, ec);
    if (ec) fail_input(root_.string(), std::nullopt, name + ": cannot stat: " + ec.message());
    return size;
  }
  Blob read(const std::string& name, std::uint64_t max_bytes, const std::string& why) const override {
    MappedFile file((root_ / name).string());  // mapped, not read: its size costs no memory yet
    if (file.size() > max_bytes)
      fail_input(root_.string(), std::nullopt,
                 name + ": holds " + std::to_string(file.size()) + " bytes, more than the " +
                     std::to_string(max_bytes) + " " + why);
    return Blob(std::move(file));
  }

 private:
  std::filesystem::path root_;
};

}  // namespace

std::unique_ptr<Members> zip_members(const std::string& path, std::span<const std::uint8_t> bytes) {
  return std::make_unique<ZipMembers>(path, bytes);
}

std::unique_ptr<Members> dir_members(const std::string& path) { return std::make_unique<DirMembers>(path); }

}  // namespace vxl::trx
