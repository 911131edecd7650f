// RenderParams: the parameters of one render, generated from params.def (the one declaration of
// every parameter, with its layer, default, unit, domain and doc). sim/pipeline.py validates the
// user's values first; the engine checks what it relies on (validate_frame_params in
// traversal/render.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "core/choice.h"

namespace rast5d {

// A [lo, hi] range of one sample coordinate (the clip box).
using CoordRange = std::array<double, 2>;

// Choice parameters held as an enum; ChoiceTraits<E> names their registry and its entries. Every
// stage's choice parameters are declared here, so no stage header needs another's for them.
enum class LensShape : int { kDisk = 0, kSquare = 1, kHexagon = 2 };
enum class OracleMode : int { kSimplified = 0, kFull = 1 };
enum class OpCount : int { kDocumented = 0, kExact = 1 };
enum class MotionTest : int { kIntervals = 0, kBounds = 1 };
enum class ZhatMode : int { kPlanes = 0, kVertex = 1 };
enum class QueryMode : int { kNone = 0, kSamples = 1, kIntervals = 2 };
enum class CostModel : int { kRobust = 0, kHardware = 1 };
enum class ZhatMargin : int { kDerived = 0, kFixed = 1 };

template <>
struct ChoiceTraits<LensShape> {
  static constexpr std::string_view registry = "lens_shapes";
  static constexpr std::array<ChoiceInfo, 3> table = {{
      {"disk", "the unit disk"},
      {"square", "[-1, 1]^2"},
      {"hexagon", "the regular hexagon inscribed in the unit circle, vertices (+-1, 0)"},
  }};
};
template <>
struct ChoiceTraits<OracleMode> {
  static constexpr std::string_view registry = "oracle_modes";
  static constexpr std::array<ChoiceInfo, 2> table = {{
      {"simplified", "N = R_S / 2 |X_q - X_p| |Y_q - Y_p| ([Akenine-Möller 2012] Eq. 15, the paper's)"},
      {"full", "N = R_S / 8 F(a, b) F(c, d) ([Akenine-Möller 2012] Eq. 9-12)"},
  }};
};
template <>
struct ChoiceTraits<OpCount> {
  static constexpr std::string_view registry = "op_counts";
  static constexpr std::array<ChoiceInfo, 2> table = {{
      {"documented", "charge each kernel's documented cost (costs.h)"},
      {"exact", "run the kernels on the counting scalar type"},
  }};
};
template <>
struct ChoiceTraits<MotionTest> {
  static constexpr std::string_view registry = "motion_tests";
  static constexpr std::array<ChoiceInfo, 2> table = {{
      {"intervals", "t̂ and lens sets per time sub-interval, samples indexed by time stratum"},
      {"bounds", "h_i lines over the shutter ends, no t̂"},
  }};
};
template <>
struct ChoiceTraits<ZhatMode> {
  static constexpr std::string_view registry = "zhat_modes";
  static constexpr std::array<ChoiceInfo, 2> table = {{
      {"planes", "moving box + moving planes ([Nilsson 2012] App. A)"},
      {"vertex", "vertex min/max"},
  }};
};
template <>
struct ChoiceTraits<QueryMode> {
  static constexpr std::string_view registry = "query_modes";
  static constexpr std::array<ChoiceInfo, 3> table = {{
      {"none", "no occlusion query"},
      {"samples", "the query's samples run the depth test (nothing written); visible iff any passes"},
      {"intervals", "ẑ of each (query triangle, tile) against HiZ, abort at the first pair that may be visible"},
  }};
};

template <>
struct ChoiceTraits<CostModel> {
  static constexpr std::string_view registry = "cost_models";
  static constexpr std::array<ChoiceInfo, 2> table = {{
      {"robust", "float32 sample-relative edge functions without FMA (watertight; docs/op_costs.md)"},
      {"hardware", "fixed-point affine edge functions A x + B y + C set up per triangle or lens position, FMA"},
  }};
};

template <>
struct ChoiceTraits<ZhatMargin> {
  static constexpr std::string_view registry = "zhat_margins";
  static constexpr std::array<ChoiceInfo, 2> table = {{
      {"derived", "per (triangle, tile): a bound on the float sample depth's own rounding error"},
      {"fixed", "12.5 % of W on both sides (the former fixed margin, for comparison)"},
  }};
};

// The arithmetic of one stage (pipeline.precision.{tile, sample, depth}; docs/precision.md): IEEE
// binary64 or binary32, or fixed point with int_bits integer and frac_bits fraction bits
// (core/fixed.h). The user writes 'float64', 'float32' or {fixed: {int_bits, frac_bits}}.
enum class PrecisionKind : int { kFloat64 = 0, kFloat32 = 1, kFixed = 2 };
struct Precision {
  PrecisionKind kind = PrecisionKind::kFloat64;
  int int_bits = 0, frac_bits = 0;  // kFixed only
  static constexpr Precision float64() { return {PrecisionKind::kFloat64, 0, 0}; }
  static constexpr Precision float32() { return {PrecisionKind::kFloat32, 0, 0}; }
  static constexpr Precision fixed(int int_bits, int frac_bits) { return {PrecisionKind::kFixed, int_bits, frac_bits}; }
  bool operator==(const Precision&) const = default;
};
// Limits of a fixed format: registers hold 1 + int_bits + 2 frac_bits bits (core/fixed.h).
inline constexpr int kFixedMaxIntBits = 62, kFixedMaxFracBits = 24, kFixedMaxRegisterBits = 100;
// std::invalid_argument naming the field unless p is a valid format.
inline void check_precision(std::string_view field, const Precision& p) {
  if (p.kind != PrecisionKind::kFixed) return;
  if (p.int_bits < 1 || p.int_bits > kFixedMaxIntBits || p.frac_bits < 0 || p.frac_bits > kFixedMaxFracBits ||
      1 + p.int_bits + 2 * p.frac_bits > kFixedMaxRegisterBits) {
    std::ostringstream msg;
    msg << field << ": expected fixed int_bits in [1, " << kFixedMaxIntBits << "] and frac_bits in [0, "
        << kFixedMaxFracBits << "] with 1 + int_bits + 2 frac_bits <= " << kFixedMaxRegisterBits << ", got int_bits "
        << p.int_bits << ", frac_bits " << p.frac_bits;
    throw std::invalid_argument(msg.str());
  }
}

// The shading parameter: a registry by name, entries in enum order.
enum class ShadingMode : int { kPerSample = 0, kMsaa = 1, kPerLensCell = 2, kCache = 3, kNone = 4 };
template <>
struct ChoiceTraits<ShadingMode> {
  static constexpr std::string_view registry = "shading_modes";
  static constexpr std::array<ChoiceInfo, 5> table = {{
      {"per_sample", "supersampling: a lane per (pixel, sample index)"},
      {"msaa", "a lane per pixel per visit"},
      {"per_lens_cell", "a lane per (pixel, lens-grid cell) per visit"},
      {"cache", "a memoising shading cache keyed by (triangle, shading-grid point) ([Nilsson 2012] §2)"},
      {"none", "shading work is not modelled (no shade.*/tex.* counts)"},
  }};
};

// The texture_filter and texture_layout parameters: registries by name, entries
// in enum order.
enum class TexFilter : int { kBilinear = 0, kTrilinear = 1 };
template <>
struct ChoiceTraits<TexFilter> {
  static constexpr std::string_view registry = "texture_filters";
  static constexpr std::array<ChoiceInfo, 2> table = {{
      {"bilinear", "nearest mip level, bilinear within it"},
      {"trilinear", "bilinear in the two nearest mip levels, blended"},
  }};
};
enum class TexLayout : int { kLinear = 0, kBlocked = 1, kMorton = 2 };
template <>
struct ChoiceTraits<TexLayout> {
  static constexpr std::string_view registry = "texture_layouts";
  static constexpr std::array<ChoiceInfo, 3> table = {{
      {"linear", "row-major texels"},
      {"blocked", "4x4 texel blocks, blocks row-major"},
      {"morton", "4x4 texel blocks in Morton order"},
  }};
};

// The gpu_constants parameter ([Toth 2008] §9.6): where the contained triangle's data lives for the
// conventional-GPU pipeline's pixel shader.
enum class GpuConstants : int { kNone = 0, kTriangle = 1, kStrip = 2 };
template <>
struct ChoiceTraits<GpuConstants> {
  static constexpr std::string_view registry = "gpu_constants";
  static constexpr std::array<ChoiceInfo, 3> table = {{
      {"none", "every bounding vertex carries the triangle's data; the pixel shader re-derives the sample-kernel setup per fragment"},
      {"triangle", "triangle constants: data once per bounding triangle, setup derived once in the geometry shader"},
      {"strip", "strip constants: data once per bounding strip, setup derived once in the geometry shader"},
  }};
};

// The depth buffer's compression scheme (hardware.depth_buffer.compression; memory/compression.h).
enum class DepthCompression : int { kNone = 0, kPlane = 1, kTimePredictor = 2 };
template <>
struct ChoiceTraits<DepthCompression> {
  static constexpr std::string_view registry = "depth_compressions";
  static constexpr std::array<ChoiceInfo, 3> table = {{
      {"none", "raw: 4 bytes per sample"},
      {"plane", "static-plane baseline: one plane over the line's written samples, delta residuals"},
      {"time_predictor",
       "up to two depth layers, each with a time-dependent plane predictor, delta residuals [Andersson 2011]"},
  }};
};

struct RenderParams {
#define RAST5D_PARAM(layer, group, key, type, def, unit, domain, doc) type group##key = def;
#define RAST5D_PY_PARAM(layer, group, key, type, def, unit, domain, doc)
#define RAST5D_PARAM_GROUP(layer, name, keys, doc)
#include "core/params.def"
#undef RAST5D_PARAM
#undef RAST5D_PY_PARAM
#undef RAST5D_PARAM_GROUP
};

// The domain check of one numeric parameter, from its params.def domain text: "[lo, hi]",
// "(lo, hi]", ... or "{a, b, c}"; other domains (registries, "") are checked elsewhere. With a user
// sentinel (" | auto", " | null") the engine default, which the sentinel stands for, is accepted.
template <class T>
void check_domain(std::string_view name, T value, T engine_default, std::string_view domain) {
  if constexpr (std::is_same_v<T, Precision>) {  // "{float64, float32, fixed}": the kinds accepted
    static constexpr std::string_view kNames[3] = {"float64", "float32", "fixed"};
    const std::string_view kind = kNames[static_cast<int>(value.kind)];
    if (domain.find(kind) == std::string_view::npos) {
      std::ostringstream msg;
      msg << name << ": expected one of " << domain << ", got " << kind;
      throw std::invalid_argument(msg.str());
    }
    check_precision(name, value);
    (void)engine_default;
  } else if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    const std::size_t bar = domain.find(" | ");
    if (bar != std::string_view::npos) {
      if (value == engine_default) return;
      domain = domain.substr(0, bar);
    }
    if (domain.size() < 2 || (domain[0] != '[' && domain[0] != '(' && domain[0] != '{')) return;
    std::vector<double> xs;
    const std::string body(domain.substr(1, domain.size() - 2));
    const char* s = body.c_str();
    for (char* end = nullptr;; s = end + 1) {
      xs.push_back(std::strtod(s, &end));
      if (*end != ',') break;
    }
    const double v = static_cast<double>(value);
    bool ok = false;
    if (domain[0] == '{') {
      for (double x : xs) ok = ok || v == x;
    } else {
      ok = (domain[0] == '(' ? v > xs[0] : v >= xs[0]) && (domain.back() == ')' ? v < xs[1] : v <= xs[1]);
    }
    if (!ok) {
      std::ostringstream msg;
      msg << name << ": expected " << domain << ", got " << value;
      throw std::invalid_argument(msg.str());
    }
  }
}

// Every numeric RenderParams field against its declared domain (std::invalid_argument otherwise).
inline void validate_domains(const RenderParams& p) {
  const RenderParams defaults;
#define RAST5D_PARAM(layer, group, key, type, def, unit, domain, doc) \
  check_domain(#group #key, p.group##key, defaults.group##key, domain);
#define RAST5D_PY_PARAM(layer, group, key, type, def, unit, domain, doc)
#define RAST5D_PARAM_GROUP(layer, name, keys, doc)
#include "core/params.def"
#undef RAST5D_PARAM
#undef RAST5D_PY_PARAM
#undef RAST5D_PARAM_GROUP
}

}  // namespace rast5d
