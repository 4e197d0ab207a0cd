#include "converter/selection/region.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <variant>

#include "format/base/error.h"

namespace vxl {
namespace {

[[noreturn]] void bad_region(const std::string& text, const std::string& why) {
  throw Error(ErrorKind::Usage, text, std::nullopt, "not a usable region: " + why);
}

// "a,b,c,..." as floats; nothing when a piece is not exactly a number (one sign, '+' or '-', at most). Each is
// read as a double and then rounded to a float, as tckedit reads a region (MRtrix's parse_floats, then its
// float geometry): a decimal that lies next to the midpoint of two floats rounds as it does there.
std::optional<std::vector<float>> parse_floats(std::string_view s) {
  std::vector<float> out;
  while (true) {
    const std::size_t comma = s.find(',');
    std::string_view piece = s.substr(0, comma);
    while (!piece.empty() && piece.front() == ' ') piece.remove_prefix(1);
    while (!piece.empty() && piece.back() == ' ') piece.remove_suffix(1);
    if (!piece.empty() && piece.front() == '+') {
      piece.remove_prefix(1);
      if (!piece.empty() && (piece.front() == '-' || piece.front() == '+')) return std::nullopt;  // "+-5"
    }
    double v = 0;
    const auto [end, ec] = std::from_chars(piece.data(), piece.data() + piece.size(), v);
    if (piece.empty() || ec != std::errc() || end != piece.data() + piece.size()) return std::nullopt;
    out.push_back(static_cast<float>(v));
    if (comma == std::string_view::npos) return out;
    s.remove_prefix(comma + 1);
  }
}

bool all_finite(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
}

}  // namespace

Region Region::sphere(Point3f centre, float radius, std::string text) {
  Region r;
  r.shape_ = Shape::Sphere;
  r.text_ = std::move(text);
  r.centre_ = centre;
  r.radius_ = radius;
  r.radius2_ = radius * radius;
  for (int c = 0; c < 3; ++c) r.lo_[c] = centre[c] - radius, r.hi_[c] = centre[c] + radius;
  return r;
}

Region Region::box(Point3f lo, Point3f hi, std::string text) {
  Region r;
  r.shape_ = Shape::Box;
  r.text_ = std::move(text);
  r.lo_ = lo;
  r.hi_ = hi;
  return r;
}

Region Region::mask(const VolumeImage& image, std::optional<float> label, std::string text) {
  Region r;
  r.shape_ = Shape::Mask;
  r.text_ = std::move(text);
  auto selected = [&](float v) { return label ? v == *label : v != 0.0f; };
  std::array<std::int64_t, 3> first{INT64_MAX, INT64_MAX, INT64_MAX}, last{-1, -1, -1};
  std::size_t at = 0;
  for (std::int64_t k = 0; k < image.dims[2]; ++k)
    for (std::int64_t j = 0; j < image.dims[1]; ++j)
      for (std::int64_t i = 0; i < image.dims[0]; ++i, ++at) {
        if (!selected(image.values[at])) continue;
        const std::int64_t index[3] = {i, j, k};
        for (int c = 0; c < 3; ++c) first[c] = std::min(first[c], index[c]), last[c] = std::max(last[c], index[c]);
      }
  if (last[0] < 0)
    bad_region(r.text_, label ? "the image holds no voxel of label " + std::to_string(*label) : "the mask is empty");

  // Looked up as tckedit looks a mask up (image_geometry.h): in the image realigned to near-RAS axes and cropped to
  // the set voxels, through its scanner-to-voxel affine in float32. Only the crop is kept, one byte a voxel in the
  // cropped realigned order, so that a mask costs what its set voxels span, not the image.
  const MaskLookup lookup = mask_lookup(image.geometry, image.dims, first, last);
  r.ras_to_voxel_ = lookup.scanner_to_voxel;
  r.dims_ = lookup.dims;
  std::vector<std::uint8_t> set(static_cast<std::size_t>(r.dims_[0] * r.dims_[1] * r.dims_[2]));
  std::size_t n = 0;
  for (std::int64_t n2 = 0; n2 < r.dims_[2]; ++n2)
    for (std::int64_t n1 = 0; n1 < r.dims_[1]; ++n1)
      for (std::int64_t n0 = 0; n0 < r.dims_[0]; ++n0, ++n) {
        const std::int64_t sample = lookup.offset + n0 * lookup.step[0] + n1 * lookup.step[1] + n2 * lookup.step[2];
        set[n] = selected(image.values[static_cast<std::size_t>(sample)]);
      }
  r.set_ = std::make_shared<const std::vector<std::uint8_t>>(std::move(set));
  const auto& a = image.voxel_to_ras;

  // The RAS box of the set voxels' cubes: the corners of [first - 1/2, last + 1/2] through the affine,
  // widened by a voxel's hundredth for the float32 lookup's rounding.
  for (int c = 0; c < 3; ++c) r.lo_[c] = INFINITY, r.hi_[c] = -INFINITY;
  for (int corner = 0; corner < 8; ++corner) {
    double index[3];
    for (int c = 0; c < 3; ++c) index[c] = (corner >> c & 1) ? double(last[c]) + 0.5 : double(first[c]) - 0.5;
    for (int row = 0; row < 3; ++row) {
      const double x = a[4 * row] * index[0] + a[4 * row + 1] * index[1] + a[4 * row + 2] * index[2] + a[4 * row + 3];
      const double margin = 0.01 * (std::abs(a[4 * row]) + std::abs(a[4 * row + 1]) + std::abs(a[4 * row + 2]));
      r.lo_[row] = std::min(r.lo_[row], static_cast<float>(x - margin));
      r.hi_[row] = std::max(r.hi_[row], static_cast<float>(x + margin));
    }
  }
  return r;
}

bool Region::contains(const float* p) const {
  switch (shape_) {
    case Shape::Sphere:  // tckedit: (pos - p).squaredNorm() <= radius^2, in float32
      return squared_distance(p) <= radius2_;
    case Shape::Box:
      return p[0] >= lo_[0] && p[0] <= hi_[0] && p[1] >= lo_[1] && p[1] <= hi_[1] && p[2] >= lo_[2] && p[2] <= hi_[2];
    case Shape::Mask: {
      // In float32, as Eigen evaluates tckedit's affine product (Transform<float, 3, AffineCompact> times a
      // point): the four terms summed in pairs (test SelectionRegions.MaskLookupRoundsAsEigensAffineProduct).
      std::int64_t index[3];
      for (int row = 0; row < 3; ++row) {
        const float v = mask_row(&ras_to_voxel_[4 * row], p);
        const float rounded = std::round(v);
        if (!(rounded >= 0.0f && rounded < float(dims_[row]))) return false;
        index[row] = static_cast<std::int64_t>(rounded);
      }
      return (*set_)[static_cast<std::size_t>(index[0] + dims_[0] * (index[1] + dims_[1] * index[2]))] != 0;
    }
  }
  return false;
}

namespace {

// A thousandth of a millimetre (relative to the coordinates' size) of slack: the float32 point tests round,
// a box test must never be the one that decides otherwise.
float slack(float a, float b) { return 1e-3f + 1e-6f * std::max(std::abs(a), std::abs(b)); }

}  // namespace

void Region::reach(float* lo, float* hi) const {
  for (int c = 0; c < 3; ++c) {
    if (shape_ == Shape::Sphere) {
      const float s = radius_ + slack(centre_[0] + centre_[1] + centre_[2], radius_);
      lo[c] = centre_[c] - s, hi[c] = centre_[c] + s;
    } else {
      const float s = slack(lo_[c], hi_[c]);
      lo[c] = lo_[c] - s, hi[c] = hi_[c] + s;
    }
  }
}

bool Region::holds_box(const float* lo, const float* hi) const {
  if (shape_ == Shape::Mask) return false;
  if (shape_ == Shape::Sphere) {
    // The farthest corner (a ball is convex: it holds the box when it holds every corner).
    double d2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = std::max(std::abs(double(lo[c]) - centre_[c]), std::abs(double(hi[c]) - centre_[c]));
      d2 += d * d;
    }
    const double reach = double(radius_) - slack(centre_[0] + centre_[1] + centre_[2], radius_);
    return reach > 0 && d2 <= reach * reach;
  }
  for (int c = 0; c < 3; ++c) {
    const float s = slack(lo_[c], hi_[c]);
    if (lo[c] < lo_[c] + s || hi[c] > hi_[c] - s) return false;
  }
  return true;
}

bool Region::may_touch(const float* lo, const float* hi) const {
  if (shape_ == Shape::Sphere) {
    double d2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double below = double(lo[c]) - centre_[c], above = double(centre_[c]) - hi[c];
      const double d = std::max({below, above, 0.0});
      d2 += d * d;
    }
    const double reach = double(radius_) + slack(centre_[0] + centre_[1] + centre_[2], radius_);
    return d2 <= reach * reach;
  }
  for (int c = 0; c < 3; ++c) {
    const float s = slack(lo_[c], hi_[c]);
    if (hi[c] < lo_[c] - s || lo[c] > hi_[c] + s) return false;
  }
  return true;
}

namespace {

// An argument naming an image: the file, and the label when one is chosen.
struct ImageArgument {
  std::string path;
  std::optional<float> label;
};

// A sphere or a box, made; or the image an argument names, checked to exist and to have an image's name.
std::variant<Region, ImageArgument> parse_argument(const std::string& text) {
  std::error_code ec;
  const bool names_file = std::filesystem::exists(text, ec);
  if (!names_file && text.starts_with("box:")) {
    const auto v = parse_floats(std::string_view(text).substr(4));
    if (!v || v->size() != 6) bad_region(text, "a box is box:X0,Y0,Z0,X1,Y1,Z1 (two corners, RAS mm)");
    if (!all_finite(*v)) bad_region(text, "a box corner is not finite");
    const Point3f lo{(*v)[0], (*v)[1], (*v)[2]}, hi{(*v)[3], (*v)[4], (*v)[5]};
    for (int c = 0; c < 3; ++c)
      if (lo[c] > hi[c])
        bad_region(text, "the box's first corner must be below its second on every axis (" + std::string(1, "xyz"[c]) +
                             ": " + std::to_string(lo[c]) + " > " + std::to_string(hi[c]) + ")");
    return Region::box(lo, hi, text);
  }
  if (!names_file) {
    if (const auto v = parse_floats(text)) {
      if (v->size() != 4) bad_region(text, "a sphere is X,Y,Z,R (centre and radius, RAS mm)");
      if (!all_finite({(*v)[0], (*v)[1], (*v)[2]})) bad_region(text, "the sphere's centre must be finite");
      if (!std::isfinite((*v)[3]))
        bad_region(text, "the sphere's radius must be a finite number of mm that a float holds (below 3.4e38)");
      if ((*v)[3] < 0) bad_region(text, "the sphere's radius is negative");
      return Region::sphere({(*v)[0], (*v)[1], (*v)[2]}, (*v)[3], text);
    }
  }
  // An image: FILE or FILE:LABEL (FILE itself may hold ':').
  std::string path = text;
  std::optional<float> label;
  if (!names_file) {
    const std::size_t colon = text.rfind(':');
    if (colon != std::string::npos && colon > 0) {
      const auto l = parse_floats(std::string_view(text).substr(colon + 1));
      if (l && l->size() == 1 && std::isfinite((*l)[0])) {
        path = text.substr(0, colon);
        label = (*l)[0];
      }
    }
  }
  if (!std::filesystem::exists(path, ec)) {
    bad_region(text, is_image_name(path)
                         ? "no such image file"
                         : "expected X,Y,Z,R (a sphere), box:X0,Y0,Z0,X1,Y1,Z1, or a mask image "
                           "(FILE.nii, FILE.nii.gz, FILE.mif, FILE.mif.gz, FILE.mih, FILE.nii.gz:LABEL)");
  }
  if (!is_image_name(path))
    throw Error(ErrorKind::Unsupported, path, std::nullopt,
                "a region image must be NIfTI (.nii, .nii.gz) or MRtrix (.mif, .mif.gz, .mih); convert other formats "
                "first (e.g. mrconvert)");
  return ImageArgument{path, label};
}

}  // namespace

std::vector<Region> parse_regions(const std::vector<std::string>& texts) {
  std::vector<std::optional<Region>> regions(texts.size());
  std::vector<std::pair<std::size_t, ImageArgument>> images;
  for (std::size_t i = 0; i < texts.size(); ++i) {
    std::variant<Region, ImageArgument> parsed = parse_argument(texts[i]);
    if (Region* r = std::get_if<Region>(&parsed))
      regions[i] = std::move(*r);
    else
      images.emplace_back(i, std::get<ImageArgument>(std::move(parsed)));
  }
  // Each file read once, in the order first named; its regions made before the next is read.
  for (std::size_t i = 0; i < images.size(); ++i) {
    const std::string& path = images[i].second.path;
    if (regions[images[i].first]) continue;
    const VolumeImage image = read_volume_image(path);
    for (std::size_t j = i; j < images.size(); ++j) {
      const auto& [at, argument] = images[j];
      if (argument.path != path || regions[at]) continue;
      regions[at] = Region::mask(image, argument.label, texts[at]);
      // The same argument again shares the voxels.
      for (std::size_t k = j + 1; k < images.size(); ++k)
        if (texts[images[k].first] == texts[at]) regions[images[k].first] = regions[at];
    }
  }
  std::vector<Region> out;
  out.reserve(regions.size());
  for (std::optional<Region>& r : regions) out.push_back(std::move(*r));
  return out;
}

Region parse_region(const std::string& text) { return std::move(parse_regions({text}).front()); }

}  // namespace vxl
