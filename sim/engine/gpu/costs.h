// Documented operation costs of the conventional-GPU pipeline (gpu/): the geometry shader's
// bounding-geometry kernels, the 2D rasterizer's edge tests and the pixel shader's per-fragment
// re-derived setup. Units as core/costs.h ([Akenine-Möller 2012] §6.2: ADD, MUL, MADD, CMP,
// MIN, MAX, RCP one each), plus SQRT counted as one operation (a special-function op like RCP).
// The fast path charges these constants per executed kernel; the counting path tallies the same
// kernels on Counted<T>, and tests/test_invariants.py (documented == exact, every algorithm)
// proves that the two agree over whole renders. docs/gpu.md explains each figure.
#pragma once

#include <cstdint>

namespace rast5d::cost::gpu {

// ---- geometry shader (gpu/geometry_shader.h; ops.setup and gpu.gs_ops) ----
inline constexpr std::uint64_t kShape = 6;         // RCP, 2 MUL position; MADD, 2 MUL confusion extents
inline constexpr std::uint64_t kOrient = 9;        // 4 SUB, 2 MUL, SUB; 2 CMP (sign, degeneracy)
inline constexpr std::uint64_t kEdgeNormal = 8;    // 2 SUB, MUL + MADD, SQRT, RCP, 2 MUL
inline constexpr std::uint64_t kBisector = 2;      // 2 ADD
inline constexpr std::uint64_t kIntersect = 13;    // det (2 MUL, SUB), CMP, RCP, 2 x (2 MUL, SUB, MUL)
// Support of one confusion shape in a direction: MADD + MUL (position), 2 MUL (extents), lens
// term (disk: MUL, MADD, SQRT; square: ADD), ADD.
inline constexpr std::uint64_t kSupportDisk = 8;
inline constexpr std::uint64_t kSupportSquare = 6;
inline constexpr std::uint64_t support_cost(bool disk) { return disk ? kSupportDisk : kSupportSquare; }
// Variable-radius triangle: circle radius per vertex (disk: MAX; square: MUL, MADD, SQRT) and the
// outer common tangent per edge (2 SUB, MUL + MADD, SQRT, RCP, 2 MUL, SUB + MUL, MADD, CMP,
// MAX + SQRT, 2 x (MUL + MADD)).
inline constexpr std::uint64_t kVRRadiusDisk = 1;
inline constexpr std::uint64_t kVRRadiusSquare = 3;
inline constexpr std::uint64_t kVRTangent = 18;
// Adaptive choice ([Toth 2008] §4.7): per vertex MUL + MADD (squared blur radius), 2 MAX, MUL + CMP.
inline constexpr std::uint64_t kAdaptiveChoice = 10;
// (2+1)D convex hull ([McGuire 2010]): 4 ADD/SUB for the corners of one confusion box; per comparison of the
// sort 3 CMP; per orientation test 4 SUB, 2 MUL, SUB, CMP; per hull edge 2 SUB, MUL + MADD.
inline constexpr std::uint64_t kHullCorners = 4;
inline constexpr std::uint64_t kHullCompare = 3;
inline constexpr std::uint64_t kHullCross = 8;
inline constexpr std::uint64_t kHullEdge = 4;
// 3D volumes ([Toth 2008] §4.4-4.5) in the view-like space (X s, Y s, W): vertex scaling 6 MUL; two edge
// vectors 6 SUB; normal 6 MUL + 3 SUB; two normalisations 2 x (MUL, 2 MADD, SQRT, RCP, 3 MUL);
// in-plane axis 6 MUL + 3 SUB; 2D coordinates 4 x (MUL, 2 MADD); degeneracy CMP; 3 x (SUB) |W - F|.
inline constexpr std::uint64_t kPlane = 6 + 6 + 9 + 16 + 9 + 12 + 1 + 3;  // 62
// Support of the three projected discs of confusion in an in-plane direction: 3D direction 2 x
// (MUL + MADD), 2 MUL, lens term (disk 3, square 1), per vertex MUL + MADD, MUL, ADD, 2 MAX.
inline constexpr std::uint64_t support3d_cost(bool disk) { return 6 + (disk ? 3 : 1) + 12 + 2; }
// Thickness along the normal: 2 MUL, lens term, 2 MAX, MUL.
inline constexpr std::uint64_t normal_extent_cost(bool disk) { return 2 + (disk ? 3 : 1) + 2 + 1; }
inline constexpr std::uint64_t kPrismVertex = 12;  // base 6 MADD, two caps 2 x 3 MADD
inline constexpr std::uint64_t kNearCheck = 1;     // CMP against the near plane
inline constexpr std::uint64_t kProject = 4;       // RCP, MUL, 2 MUL
inline constexpr std::uint64_t kClipPair = 10;     // 2 SUB, RCP, MUL, 2 x (SUB + MADD), 2 MUL

// ---- 2D rasterizer (gpu/raster2d.h; ops.tile) ----
inline constexpr std::uint64_t kRasterEdgeSetup = 2;  // 2 CMP: the pixel corner that tests the edge
inline constexpr std::uint64_t kRasterScanVertex = 4; // 2 MIN, 2 MAX: scan box of the output vertices
inline constexpr std::uint64_t kRasterEdge = 3;       // per pixel and edge: MUL + MADD, CMP

// ---- pixel shader (traversal/algorithms/gpu_pipeline.h; ops.ps_setup) ----
// Sample-kernel constants the pixel shader re-derives per fragment without triangle constants
// ([Toth 2008] §9.6): static shear coefficients 6 MADD (core kSetupShear); motion deltas 9 SUB.
inline constexpr std::uint64_t kRederiveShear = 6;
inline constexpr std::uint64_t kRederiveMotion = 9;
// Perturbation texture ([Toth 2008] §5.3): its texture coordinate is the fragment's screen position
// scaled to one texel per pixel of the repeating block, 2 MUL per fragment; then one texel fetch
// (u, v, t: a 16-byte RGBA32F texel) per sample, counted in gpu.perturb_fetches, not in ops.
inline constexpr std::uint64_t kPerturbCoord = 2;
inline constexpr std::uint64_t kPerturbTexelBytes = 16;

// ---- accumulation buffering's passes ([Toth 2008] §2.2; traversal/algorithms/interleave.cpp, docs/gpu.md) ----
// The vertex shader's clip-space transform that a GPU repeats in every pass after the first: a 4 x 4
// matrix times the position, 4 MUL + 12 MADD, per vertex and shutter end (a moving vertex has a
// position at each end). Charged at this documented cost, not executed: the engine's vertices arrive in
// clip space (the first pass's transform is the one every algorithm needs, not counted).
inline constexpr std::uint64_t kVertexTransform = 16;
// The accumulation buffer, RGBA at 16 bits a channel: the first pass writes it, every later pass reads
// and writes it, the last one's sum is resolved into the displayed pixel (the resolve every algorithm
// pays): 2 x kAccumPixelBytes x (passes - 1) DRAM bytes per pixel.
inline constexpr std::uint64_t kAccumPixelBytes = 8;

}  // namespace rast5d::cost::gpu
