#include "viewer/render/line_shaders.h"

#include "viewer/render/clip_planes.h"
#include "viewer/render/colormap.h"

namespace vxl::shaders {

namespace {

// The version line and the sizes the vertex shader is generated for.
std::string vertex_defines(unsigned span_count, const char* version) {
  return std::string(version) + "\n#define SPANS " + std::to_string(span_count) + "\n#define CLIPS " +
         std::to_string(kMaxClipDistances) + "\n#define GROUPS " + std::to_string(kShaderGroups) +
         "\n#define SAMPLES " + std::to_string(kColormapSamples) + "\n";
}

// Each span's samplers, and one function per buffer kind choosing the span's sampler (GLSL 3.30 cannot
// index sampler arrays with a computed index).
std::string span_fetchers(unsigned span_count) {
  std::string s;
  for (unsigned c = 0; c < span_count; ++c) {
    std::string i = std::to_string(c);
    s += "uniform BUFFER_SAMPLER u_words" + i + ";\nuniform BUFFER_SAMPLER u_ord" + i +
         ";\nuniform BUFFER_SAMPLER u_dat" + i + ";\nuniform BUFFER_SAMPLER u_att" + i + ";\n";
  }
  s += "uvec4 fetch_words(int c, int t) {\n";
  for (unsigned c = 0; c < span_count; ++c)
    s += "  if (c == " + std::to_string(c) + ") return FETCH_BUFFER(u_words" + std::to_string(c) + ", t);\n";
  s += "  return uvec4(0u);\n}\nuint fetch_order_word(int c, int j) {\n";
  for (unsigned c = 0; c < span_count; ++c)
    s += "  if (c == " + std::to_string(c) + ") return FETCH_BUFFER(u_ord" + std::to_string(c) + ", j).r;\n";
  s += "  return 0u;\n}\nint fetch_dataset(int c, int j) {\n";
  for (unsigned c = 0; c < span_count; ++c)
    s += "  if (c == " + std::to_string(c) + ") return int(FETCH_BUFFER(u_dat" + std::to_string(c) + ", j).r);\n";
  s += "  return 0;\n}\nuvec2 fetch_attributes(int c, int v) {\n";
  for (unsigned c = 0; c < span_count; ++c)
    s += "  if (c == " + std::to_string(c) + ") return FETCH_BUFFER(u_att" + std::to_string(c) + ", v).rg;\n";
  s += "  return uvec2(0u);\n}\n";
  return s;
}

// The spans' layout uniforms and the packed position decoder.
const char* const kSpanLayout = R"(
// The spans' layout (scene_layout.h): S padded segments per slot, K slots, V padded vertices, the voxels,
// where the segment and vertex tables start (in words), the order buffer's words. Every index into a span's
// buffers is clamped to them: a damaged file draws wrong lines, never reads outside a buffer.
uniform int u_span_base[SPANS];
uniform int u_span_segments[SPANS];
uniform int u_span_slots[SPANS];
uniform int u_span_vertices[SPANS];
uniform int u_span_voxels[SPANS];
uniform int u_span_segment_table[SPANS];
uniform int u_span_vertex_table[SPANS];
uniform int u_span_order_words[SPANS];
const uint kVoxlineEnd = 0x40000000u;
uint fetch_word(int c, int i) { return fetch_words(c, i >> 2)[i & 3]; }
// The voxel a table entry names, and its three info texels (scene_layout.h, TextureSpan::kInfoWords).
int table_voxel(int c, int i) { return clamp(int(fetch_word(c, i)), 0, u_span_voxels[c] - 1); }
uvec4 fetch_info(int c, int voxel, int texel) { return fetch_words(c, (u_span_vertices[c] >> 2) + 3 * voxel + texel); }
// `bits` bits (1 to 32) from bit `bit` of the span's orders, least significant first (.vxl spec §5.5).
uint order_bits(int c, uint bit, uint bits) {
  int last = u_span_order_words[c] - 1;
  int w = min(int(bit >> 5u), last);
  uint shift = bit & 31u;
  uint value = fetch_order_word(c, w) >> shift;
  if (shift + bits > 32u) value |= fetch_order_word(c, min(w + 1, last)) << (32u - shift);
  return bits >= 32u ? value : value & ((1u << bits) - 1u);
}
// A packed position (.vxl spec §5.4) of the voxel whose first two info texels are `lo_step`, `rest`.
vec3 decode(uint word, uvec4 lo_step, uvec4 rest) {
  vec3 q = vec3(float(word & 1023u), float((word >> 10) & 1023u), float((word >> 20) & 1023u));
  vec3 step = uintBitsToFloat(uvec3(lo_step.w, rest.x, rest.y));
  return uintBitsToFloat(lo_step.xyz) + q * step;
}
)";

// The vertex shader's uniforms and outputs.
const char* const kVertexInterface =
    R"(uniform vec3 u_eye_hi;      // eye position split in two floats on the CPU (in double):
uniform vec3 u_eye_lo;      // p - eye = (p - hi) - lo keeps the source precision far from the origin
uniform mat3 u_rotation;    // world -> eye
uniform mat4 u_projection;
uniform int u_color_mode;   // 0 direction, 1 fixed, 2 scalar, 3 group
uniform vec3 u_fixed_color;
uniform int u_attributes;   // 1: read (value bits, streamline) per vertex (vertex_attributes.h)
uniform BUFFER_SAMPLER u_streamline_group;  // per streamline of the scene: its group mod GROUPS
uniform vec2 u_range;       // value -> t = (value - x) / (y - x)
uniform vec4 u_group[GROUPS];  // per group (index mod GROUPS): colour, opacity factor
uniform float u_opacity;
uniform vec4 u_clip[CLIPS];  // slab and clip half-spaces, camera-relative: dot(n, p - eye) + d >= 0 is kept
uniform int u_clip_count;
uniform int u_lighting;     // 0 off, 1 illuminated lines
uniform vec3 u_light;       // towards the light, eye space
uniform vec4 u_light_terms; // ambient, diffuse, specular, shininess
uniform int u_orthographic;
#if CLIP_DISTANCES
out float gl_ClipDistance[CLIPS];
#endif
out vec4 v_color;           // colour (unless mapped) and alpha
out vec2 v_light;           // lighting: colour * x + y (1, 0 when off)
out float v_value;          // colour-map position, unclamped: mapped per fragment, so long segments are exact
out float v_mapped;         // 1: colour from the map at v_value
out float v_depth;          // distance along the view axis, mm

)";

// main(), first half: the virtual vertex id -> the span, the voxel and the segment's two ends.
const char* const kVertexSegmentEnds = R"(void main() {
  int id = gl_VertexID;
  int c = 0;
  for (int k = 1; k < SPANS; ++k)
    if (id >= u_span_base[k]) c = k;
  int local = id - u_span_base[c];
  int seg = local >> 1;
  int end = local & 1;  // which end of the segment this id is
  int S = u_span_segments[c];
  int A = u_span_slots[c] * S;
  int voxel;            // span-local voxel index
  int v;                // the segment's first vertex, in the span's words
  bool dropped = false; // a block-order id whose vertex ends its voxline: no segment
  bool ordered = false; // a slot entry: v is the block's first vertex plus the entry
  uint entry = 0u;
  if (seg < 2 * A) {
    int j = seg;        // entry in the slots
    if (seg >= A) {
      int r = seg - A;
      int slot = r / S;
      j = slot * S + (S - 1 - (r - slot * S));
    }
    int slot = j / S;
    int at = j - slot * S;
    voxel = table_voxel(c, u_span_segment_table[c] + (at >> 5));
    // Entry `at - seg_first` of the voxel's order `slot`, as the file stores it; the arrays follow one
    // another, each starting on a byte.
    uvec4 orders = fetch_info(c, voxel, 2);  // seg_first, segment count, bits, order word
    uint n = uint(clamp(at - int(orders.x), 0, max(int(orders.y) - 1, 0)));
    uint array_bits = ((orders.y * orders.z + 7u) >> 3) << 3;
    entry = order_bits(c, (orders.w << 5) + uint(slot) * array_bits + n * orders.z, orders.z);
    ordered = true;
  } else if (seg < 2 * A + u_span_vertices[c]) {
    v = seg - 2 * A;
    voxel = table_voxel(c, u_span_vertex_table[c] + (v >> 5));
    dropped = (fetch_word(c, v) & kVoxlineEnd) != 0u;
  } else {
    v = clamp(fetch_dataset(c, seg - 2 * A - u_span_vertices[c]), 0, max(u_span_vertices[c] - 2, 0));
    voxel = table_voxel(c, u_span_vertex_table[c] + (v >> 5));
  }
  // A dropped id becomes a line of length zero at its vertex, which rasterises to nothing: cheaper than a
  // line outside the clip volume, which llvmpipe sends through its clipper (basic mode took 1.6x longer).
  if (dropped) end = 0;
  uvec4 lo_step = fetch_info(c, voxel, 0);
  uvec4 rest = fetch_info(c, voxel, 1);  // step.y, step.z, vertex_first, vertex count
  // The entry's segment (entry, entry + 1) of the block: an entry past the block's last segment is clamped to it.
  if (ordered) v = int(rest.z) + int(min(entry, max(rest.w, 2u) - 2u));
  vec3 p = decode(fetch_word(c, v + end), lo_step, rest);
  vec3 q = decode(fetch_word(c, v + 1 - end), lo_step, rest);
  if (dropped) q = p;
)";

// main(), second half: clip distances, colour, opacity, value, lighting and position of the segment end.
const char* const kVertexShading = R"(  vec3 rel = (p - u_eye_hi) - u_eye_lo;
  vec3 e = u_rotation * rel;
#if CLIP_DISTANCES
  for (int i = 0; i < CLIPS; ++i) gl_ClipDistance[i] = i < u_clip_count ? dot(u_clip[i].xyz, rel) + u_clip[i].w : 1.0;
#endif
  v_depth = -e.z;
  vec3 d = q - p;
  float len = length(d);
  vec3 color = u_color_mode == 0 ? (len > 0.0 ? abs(d / len) : vec3(1.0)) : u_fixed_color;
  float alpha = u_opacity;
  v_mapped = 0.0;
  v_value = 0.0;
  bool hidden = false;
  if (u_attributes != 0) {
    uvec2 a = fetch_attributes(c, v + end);
    float value = uintBitsToFloat(a.x);
    vec4 group = u_group[int(FETCH_BUFFER(u_streamline_group, int(a.y)).r) % GROUPS];
    alpha *= group.a;
    // A missing or non-finite value keeps the fixed colour.
    if (u_color_mode == 2 && !isnan(value) && !isinf(value)) {
      v_mapped = 1.0;
      v_value = (value - u_range.x) / (u_range.y - u_range.x);
    }
    if (u_color_mode == 3) color = group.rgb;
    hidden = group.a <= 0.0;
  }
  v_light = vec2(1.0, 0.0);
  if (u_lighting != 0 && len > 0.0) {
    // Illuminated lines (line_lighting.h), in eye space. Both ends use the same tangent sign, so the
    // interpolated tangent never passes through zero.
    vec3 t = normalize(u_rotation * (end == 0 ? d : -d));
    vec3 view = u_orthographic != 0 ? vec3(0.0, 0.0, 1.0) : normalize(-e);
    float lt = dot(u_light, t), vt = dot(view, t);
    float diffuse = sqrt(max(0.0, 1.0 - lt * lt));
    float specular = pow(max(0.0, diffuse * sqrt(max(0.0, 1.0 - vt * vt)) - lt * vt), u_light_terms.w);
    v_light = vec2(u_light_terms.x + u_light_terms.y * diffuse, u_light_terms.z * specular);
  }
  v_color = vec4(color, alpha);
  // A hidden group (opacity 0): both ends at the segment's first end, a line of length zero, which rasterises to
  // nothing in every mode. Not outside the clip volume: llvmpipe then sends the draw's lines through its clipper.
  if (hidden && end == 1) e = u_rotation * ((q - u_eye_hi) - u_eye_lo);
  gl_Position = u_projection * vec4(e, 1.0);
}
)";

}  // namespace

std::string line_vertex(unsigned span_count, const char* version) {
  return vertex_defines(span_count, version) + span_fetchers(span_count) + kSpanLayout + kVertexInterface +
         kVertexSegmentEnds + kVertexShading;
}

std::string line_fragment(const char* body, const char* version, bool slice_test) {
  // The line's colour: from the colour map per fragment, or the vertex colour; then the lighting terms.
  return std::string(version) + "\n#define SAMPLES " + std::to_string(kColormapSamples) + "\n#define SLICE_TEST " +
         (slice_test ? "1" : "0") + R"(
in vec4 v_color;
in vec2 v_light;
in float v_value;
in float v_mapped;
in float v_depth;
uniform vec3 u_colormap[SAMPLES];  // colormap.h: samples at t = k / (SAMPLES - 1), linear in between
vec3 colormap(float t) {
  float x = clamp(t, 0.0, 1.0) * float(SAMPLES - 1);
  int i = min(int(x), SAMPLES - 2);
  return mix(u_colormap[i], u_colormap[i + 1], x - float(i));
}
uniform sampler2D u_slice_depth;  // slice_renderer.h: window depth of the nearest opaque slice (1: none)
uniform int u_slice_test;         // 1: slices are drawn this frame
// The depth test against the opaque slices, done here rather than by the depth buffer so that it holds
// in every mode, including the multipass ones and exact's per-pixel lists.
void discard_behind_slices() {
#if SLICE_TEST
  if (u_slice_test != 0 && gl_FragCoord.z > texelFetch(u_slice_depth, ivec2(gl_FragCoord.xy), 0).r) discard;
#endif
}
vec4 line_color() {
  vec3 base = v_mapped > 0.5 ? colormap(v_value) : v_color.rgb;
  return vec4(base * v_light.x + vec3(v_light.y), v_color.a);
}
)" + body;
}

const char* const kLineOverFragment = R"(
out vec4 frag;
void main() {
  discard_behind_slices();
  frag = line_color();
}
)";

const char* const kLineWboitAccumFragment = R"(
out vec4 accum;
void main() {
  discard_behind_slices();
  vec4 c = line_color();
  float a = c.a;
  // Weight function (7) of McGuire & Bavoil 2013, with depth in mm scaled to their units.
  float z = v_depth / 200.0;
  float w = a * clamp(0.03 / (1e-5 + pow(z, 4.0)), 1e-2, 3e3);
  accum = vec4(c.rgb * a * w, a * w);
}
)";

const char* const kLineWboitRevealFragment = R"(
out vec4 reveal;
void main() {
  discard_behind_slices();
  reveal = vec4(v_color.a);
}
)";

const char* const kLineAdditiveFragment = R"(
out vec4 frag;
void main() {
  discard_behind_slices();
  vec4 c = line_color();
  frag = vec4(c.rgb * c.a, c.a);
}
)";

const char* const kFullscreenVertex = R"(#version 330 core
out vec2 v_uv;
void main() {
  vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
  v_uv = p;
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

const char* const kWboitCompositeFragment = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_accum;
uniform sampler2D u_reveal;
out vec4 frag;
void main() {
  vec4 accum = texture(u_accum, v_uv);
  float revealage = texture(u_reveal, v_uv).r;
  if (revealage >= 1.0) discard;
  vec3 color = accum.rgb / max(accum.a, 1e-5);
  frag = vec4(color, 1.0 - revealage);  // blended over the background (or the slices drawn there)
}
)";

const char* const kAdditiveCompositeFragment = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_opaque;    // depth-tested pass, alpha 1 where a line is
uniform sampler2D u_additive;  // sum of alpha * colour
uniform float u_opacity;
out vec4 frag;
void main() {
  vec4 o = texture(u_opaque, v_uv);
  vec4 s = texture(u_additive, v_uv);
  vec3 add = min(s.rgb, vec3(1.0));
  float add_a = min(s.a, 1.0);
  // Mix the two renders by the opacity: opaque at 1, additive as it goes to 0.
  vec3 color = mix(add, o.rgb * o.a, u_opacity);
  float alpha = mix(add_a, o.a, u_opacity);
  if (alpha <= 0.0) discard;
  frag = vec4(color / alpha, alpha);
}
)";

}  // namespace vxl::shaders
