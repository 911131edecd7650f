// Documented operation costs of every kernel (ops per executed kernel; ADD, MUL, MADD, CMP, MIN,
// MAX and RCP count one each, [Akenine-Möller 2012] §6.2). The fast path charges these
// constants; tests/test_op_costs.py runs each kernel on the counting scalar type and checks that
// the tallies equal them, and test_invariants checks whole renders in both modes agree.
// docs/op_costs.md explains each figure.
#pragma once

#include <cstdint>

namespace rast5d::cost {

// ---- triangle setup (setup/setup.h) ----
inline constexpr std::uint64_t kSetupMotion = 9;       // dX, dY, dW: 9 SUB
inline constexpr std::uint64_t kSetupShear = 6;        // static cx, cy: 6 MADD
inline constexpr std::uint64_t kBoundsPoint = 7;       // RCP, 2 MUL, 2 MIN, 2 MAX
inline constexpr std::uint64_t kBoundsPointLens = 14;  // RCP, 2 MUL, MADD, 2 MUL, 4 ADD, 2 MIN, 2 MAX
inline constexpr std::uint64_t kFrontCheck = 3;        // 3 CMP: every vertex in front of the eye (W > 0)

// ---- tile tests (tiletest/) ----
inline constexpr std::uint64_t kLensVertexBase = 6;     // RCP, 2 MUL, MADD, 2 MUL
inline constexpr std::uint64_t kLensVertexAxis = 2;     // per axis with a line: RCP, MUL
inline constexpr std::uint64_t kGapVertex = 4;          // per vertex per axis: 2 MADD, MIN, MAX
inline constexpr std::uint64_t kGapVertexInFocus = 2;   // 2 CMP
inline constexpr std::uint64_t kAxisSetGap = 5;         // 5 CMP per gap that is not blocked
// axis_cells: 1 MADD per finite cut end (= AxisSet::n_cmp); per-sample axis_pass: n_cmp CMP
inline constexpr std::uint64_t kBoxDisk = 7;            // 2 MIN, 2 MAX, MUL, MADD, CMP
inline constexpr std::uint64_t kBoxHexagon = 14;        // 4 MUL, 4 MADD, 6 CMP
inline constexpr std::uint64_t kEdgeSetup = 25;         // q x r, d, line constants, v
inline constexpr std::uint64_t kEdgeSetupParallel = 17; // d_w == 0: no focus-plane intersection
inline constexpr std::uint64_t kTangentCorners = 4;     // 4 CMP (0 for parallel edges)
inline constexpr std::uint64_t kLineAtCorner = 4;       // 4 MADD
inline constexpr std::uint64_t kLineCellsBase = 7;      // 2 CMP, 2 MUL, 2 MADD, ADD; + rows + 2/cell
inline constexpr std::uint64_t kEdges2DSetup = 28;      // 3 edges x 3 x (MUL + MADD), det 3, CMP, 6 CMP
inline constexpr std::uint64_t kTile2D = 9;             // 3 x (2 MADD + CMP)
inline constexpr std::uint64_t kBBoxTile = 4;           // 4 CMP against the triangle's bounds
inline constexpr std::uint64_t kOrientation = 45;       // 3 det (9 each), 2 MUL, 4 corners x (2 ADD, 2 CMP)
inline constexpr std::uint64_t kOracleSimplified = 6;   // per edge: 2 SUB, 3 MUL, CMP ([Akenine-Möller 2012] Eq. 15, 13)
inline constexpr std::uint64_t kOracleFull = 18;        // per edge: 4 SUB, 2 x F(a,b) (5 each), 3 MUL, CMP
inline constexpr std::uint64_t kOracleBudget = 1;       // per triangle: MUL (tiles x tile cost)
// Screen bounds over a lens box (tiletest/box_bounds.h, box_bounds_cost): per vertex 2 MIN + 2 MAX
// into the bounds; per vertex and axis with a line (off the focus plane) 1 MADD for one lens
// point, 2 MADD (both box ends) for a lens box.
inline constexpr std::uint64_t kBoxBoundsVertex = 4;
inline constexpr std::uint64_t kBoxBoundsAxisPoint = 1;
inline constexpr std::uint64_t kBoxBoundsAxisBox = 2;
// LAINE's per-sample lens-region test against an empty region (u_min > u_max): 4 CMP that fail.
inline constexpr std::uint64_t kSampleRegionEmpty = 4;
// H5: H_j lines extended to time for moving triangles (intervals/halfspace_5d.h).
// Setup per sub-interval with every vertex in front: 2 MUL (K F); per edge 2 x the 7 constants
// (Q 6, d 3, a0 2, a1 1, b0 2, b1 1), Δq and Δr 6 SUB, Q2 = Δq x Δr 6, 2 MUL, 7 SUB (f1 - f0).
inline constexpr std::uint64_t kH5EdgeFields = 15;
inline constexpr std::uint64_t kH5SubEdges = 2 + 3 * (2 * kH5EdgeFields + 6 + 6 + 2 + 7);  // 155
// Orientation per lens corner (4 with a lens, 1 without): shear 12 MADD (lens only), 8 det (9
// each), 4 ADD (Bernstein sums), 3 ADD + 2 MUL (margin), 8 CMP.
inline constexpr std::uint64_t kH5OrientCorner = 72 + 4 + 5 + 8;
inline constexpr std::uint64_t kH5SubSetup5D = kH5SubEdges + 4 * (12 + kH5OrientCorner);  // 559
inline constexpr std::uint64_t kH5SubSetup3D = kH5SubEdges + kH5OrientCorner;             // 244
// Selective oracle per sub-interval ([Akenine-Möller 2012] Eq. 15 and 13): mid vertices 3 x (3 x (ADD + MUL) + RCP +
// 2 MUL), budget MUL, per edge 2 SUB, 3 MUL, CMP.
inline constexpr std::uint64_t kH5Oracle = 3 * 9 + 1 + 3 * 6;  // 46
// Per (tile, sub-interval): s_lo, s_hi 2 MADD, SUB, 2 MUL (remainder factor), 2 SUB (s - 1).
inline constexpr std::uint64_t kH5TileBase = 7;
// Per edge: the constants at both ends of t̂_k, 2 MADD each (5D: 7 constants, 3D: cx, cy, c0).
inline constexpr std::uint64_t kH5EdgeEnds5D = 2 * 7 * 2;  // 28
inline constexpr std::uint64_t kH5EdgeEnds3D = 2 * 3 * 2;  // 12
// Per corner: C2 2 MADD, ρ (5D: 2 ADD + MUL; 3D: MUL); per end the line (5D: 4 MADD + MADD for
// σ C + ρ; 3D: 2 MADD + MADD + CMP).
inline constexpr std::uint64_t kH5Corner5D = 2 + 3 + 2 * 5;  // 15
inline constexpr std::uint64_t kH5Corner3D = 2 + 1 + 2 * 4;  // 11
// Per corner line and end: the box pre-test over the cells' rectangle (2 CMP signs, 4 MADD, 2 CMP);
// lines that straddle the box then cost line_cells_cost (tiletest/halfspace_edges.h).
inline constexpr std::uint64_t kH5LineBox = 8;
// Per edge: the first corner, from the signs of Q_x and Q_y at the lens centre (2 CMP).
inline constexpr std::uint64_t kH5CornerOrder = 2;
// Per edge: the support corner, the signs of the corner gradient (b1 v + cx, a1 u + cy) over the
// lens rectangle and t̂_k: 5D 8 MADD, 6 MIN + 6 MAX, 2 MUL (s^2 terms), 4 CMP; 3D 2 MIN + 2 MAX,
// 2 MUL, 4 CMP.
inline constexpr std::uint64_t kH5Support5D = 8 + 12 + 2 + 4;  // 26
inline constexpr std::uint64_t kH5Support3D = 4 + 2 + 4;       // 10

// ---- time intervals t̂ and the clip box (intervals/time_interval.h, intervals/clip.h) ----
inline constexpr std::uint64_t kFormCull = 7;  // SUB, RCP, MUL, 2 CMP, MAX, MIN
// Per (tile, sub-interval), excluding the forms: 4 edges x (MAX, MIN) against the W-valid
// interval, 2 x 4 passes x 4 edges x 2 CMP for the hull of the complement, MADD x 2 back to t,
// MAX + MIN against the clip box, CMP for emptiness.
inline constexpr std::uint64_t kTimeHull = 8 + 64 + 2 + 2 + 1;
// 3D: per edge, 3 vertices x 2 ends MADD (distance) + 3 forms.
inline constexpr std::uint64_t kTimeInterval3D = 4 * (6 + 3 * kFormCull) + kTimeHull;  // 185
// 5D: 12 MADD per axis (shear at the two lens corners), per edge 12 MADD + 6 forms.
inline constexpr std::uint64_t kTimeInterval5D = 24 + 4 * (12 + 6 * kFormCull) + kTimeHull;  // 317
// Per sub-interval setup (tile independent): per end and vertex 3 MADD lerp; 5D: 2 MADD shear
// slopes (MADD + MUL per axis); the W-valid interval: 3 x (SUB for each end) + 3 forms.
inline constexpr std::uint64_t kSubSetup3D = 2 * 9 + 3 * (2 + kFormCull);      // 45
inline constexpr std::uint64_t kSubSetup5D = kSubSetup3D + 2 * 3 * 4;          // 69
// Clip box applied to one axis' interval list: MAX + MIN per interval.
inline constexpr std::uint64_t kClipInterval = 2;
// Moving triangles in TILE: per active sub-interval and tile, t̂_k to time strata (2 MUL); per
// selected sample, t against t̂_k (2 CMP) and against each clipped lens axis (2 CMP).
inline constexpr std::uint64_t kTimeStrata = 2;
inline constexpr std::uint64_t kSampleTime = 2;
inline constexpr std::uint64_t kSampleClipAxis = 2;

// ---- sample test (sampletest/kernels.h) ----
inline constexpr std::uint64_t kEdges = 18;      // 6 MADD relative coords, 3x(2 MUL + SUB), det 3
inline constexpr std::uint64_t kSigns = 4;       // sign(det), 3 sign(e_i)
inline constexpr std::uint64_t kShear = 6;       // 6 MADD
inline constexpr std::uint64_t kLerp = 9;        // 9 MADD
inline constexpr std::uint64_t kShearMoving = 12;  // 6 MADD coefficients + 6 MADD shear
inline constexpr std::uint64_t kTieBreak = 12;   // per zero edge: 4 MADD, 2x(2 MUL + SUB), 2 CMP

inline constexpr std::uint64_t kInside2D = kEdges + kSigns;                        // 22
inline constexpr std::uint64_t kInside3D = kLerp + kEdges + kSigns;                // 31
inline constexpr std::uint64_t kInside4D = kShear + kEdges + kSigns;               // 28
inline constexpr std::uint64_t kInside5D = kLerp + kShearMoving + kEdges + kSigns;  // 43

// ---- sample test, hardware cost model (pipeline.cost_model: hardware; sampletest/hardware.h) ----
// What a fixed-point datapath with fused multiply-add would execute. Vertices snapped to a fixed
// point grid make every edge function exact, so neither the sample-relative form nor the
// two-products-and-a-subtraction form of the robust kernels is needed, and the decisions equal
// the robust kernels' (docs/op_costs.md). 2D (static in focus, or a static triangle at one
// discrete lens position): affine edge functions e_i = A_i x + B_i y + C_i, set up once per
// triangle or lens position (cost::kEdges2DSetup, charged to ops.setup), oriented and biased for
// the top-left rule at setup, so a test is 3 x 2 MADD + 3 CMP and a tie costs nothing.
inline constexpr std::uint64_t kHwAffine2D = 6;   // 3 x (2 MADD): A x + B y + C
inline constexpr std::uint64_t kHwSigns2D = 3;    // 3 CMP (det's sign is folded into the setup)
// 3D/4D/5D (the vertices move with the sample's (u, v, t)): vertices placed as in the robust
// kernels (kLerp, kShear, kShearMoving), 6 MADD relative coordinates, 3 x (MUL + MADD) edge
// functions, det MUL + 2 MADD, 4 sign tests.
inline constexpr std::uint64_t kHwEdges = 6 + 6 + 3;  // 15
inline constexpr std::uint64_t kHwInside2D = kHwAffine2D + kHwSigns2D;              // 9
inline constexpr std::uint64_t kHwInside3D = kLerp + kHwEdges + kSigns;               // 28
inline constexpr std::uint64_t kHwInside4D = kShear + kHwEdges + kSigns;              // 25
inline constexpr std::uint64_t kHwInside5D = kLerp + kShearMoving + kHwEdges + kSigns;  // 40
inline constexpr std::uint64_t kHwTieBreak = 6;    // per zero edge: gradient 2 x (MUL + MADD), 2 CMP
inline constexpr std::uint64_t kHwTieBreak2D = 0;  // folded into the affine set-up's bias

// ---- covered samples (backend/sample_backend.h; same for all algorithms; ops.interp) ----
inline constexpr std::uint64_t kDepth = 6;      // 2 ADD, RCP, MUL, MADD, CMP (near plane)
inline constexpr std::uint64_t kDepthTest = 1;  // CMP against the depth buffer
inline constexpr std::uint64_t kColor = 13;     // RCP, 3 MUL, 3x(MUL + 2 MADD)

// ---- depth intervals ẑ (intervals/depth_interval.h) ----
// Documented costs of ẑ. Vertex test (the moving box in W over t̂; W is linear in t): per vertex
// 2 MADD (ends) + 2 MIN + 2 MAX, near clamp MAX, z = 1 - near / W twice (RCP + MADD).
inline constexpr std::uint64_t kZhatVertex = 3 * 6 + 1 + 2 + 2;  // 23
// Moving planes, per triangle: t = 1 vertices 9 ADD; per base time 6 SUB (edges), 3 x (MUL +
// MADD) normal, MUL + 2 MADD offset, 3 x 3 MADD distances, 2 MAX + 2 MIN.
inline constexpr std::uint64_t kZhatPlaneSetup = 9 + 2 * (6 + 6 + 3 + 9 + 4);  // 65
// Per plane (4 planes) and tile: per lens corner (u, v) [1 or 4]: per screen corner 2 MADD + 2 CMP
// (+2 MADD ray offset with lens), the lens term (4 MUL + 2 MADD with lens), 2 MADD time terms;
// per (lens, screen) corner RCP + 2 x (MUL + MIN/MAX); MIN + MAX into the bound.
inline constexpr std::uint64_t kZhatPlaneTile3D = 4 * (1 * (4 * 4 + 0 + 2) + 4 * 5 + 2);  // 160
inline constexpr std::uint64_t kZhatPlaneTile5D = 4 * (4 * (4 * 6 + 6 + 2) + 16 * 5 + 2);  // 840
inline constexpr std::uint64_t zhat_plane_cost(bool lens) { return lens ? kZhatPlaneTile5D : kZhatPlaneTile3D; }
// ẑ against the HiZ tile (backend/zcull.h): 2 CMP (zmax, zmin).
inline constexpr std::uint64_t kHiZCompare = 2;

// ---- line samples (lines/coverage.h, lines/segment_buffer.h; [Tzeng 2012] §3-4) ----
// Per (screen point, triangle): 6 MADD relative coordinates; per edge e 2 MUL + SUB, d/du and d/dv
// MUL + MADD each; det, d/du, d/dv MUL + 2 MADD each; sum and its gradients 2 ADD each; the near
// function and its gradients 3 MADD.
inline constexpr std::uint64_t kLinePointSetup = 6 + 3 * 7 + 9 + 6 + 3;  // 45
// Per (line, triangle): slopes along the line of e_0..2, det, sum (MUL + MADD each; + 2 for the
// near function), per function a sign test of the slope and then RCP, MUL, MIN, MAX for a root
// (or one sign test of the constant for a zero slope), 2 CMP for the two candidate intervals.
inline constexpr std::uint64_t line_interval_cost(int n_fns, int n_flat) {
  return 10 + (n_fns == 5 ? 2 : 0) + 5 * static_cast<std::uint64_t>(n_fns - n_flat) +
         2 * static_cast<std::uint64_t>(n_flat) + 2;
}
// Tile clip: per uv-box and tile the pseudo-angle interval of its corners (data dependent, counted
// in lines/coverage.h box_angles()); per line and box tested 2 CMP against the interval.
inline constexpr std::uint64_t kLineAngleTest = 2;
inline constexpr std::uint64_t kLineBoxWiden = 4;  // per uv-box and tile: 2 SUB, 2 ADD
inline constexpr std::uint64_t kLineBoxCentre = 4;  // per uv-box and tile: 4 CMP (does it hold the lens centre?)
// Segment shading at its midpoint (ops.interp): ADD + MUL midpoint, 3 MADD e_i, 2 ADD sum,
// MADD det, RCP + MUL + MADD depth, RCP + 3 MUL barycentrics, 3 x (MUL + 2 MADD) colour.
inline constexpr std::uint64_t kLineShade = 2 + 3 + 2 + 1 + 3 + 4 + 9;  // 24
inline constexpr std::uint64_t kLineDepth = 5;  // 2 MADD, RCP, MUL, MADD
inline constexpr std::uint64_t kKappa = 4;      // 2 MUL, SUB, MUL
// A new segment: κ, depth at both ends, MIN + MAX of them (the too-small CMP is charged after the
// merge test, for segments that did not merge).
inline constexpr std::uint64_t kSegNew = kKappa + 2 * kLineDepth + 2;  // 16
// Merging two segments: MIN, MAX, ADD, RCP, 3 x (MUL, MADD, MUL) colour, κ, MIN, MAX, MIN depths.
inline constexpr std::uint64_t kSegMerge = 4 + 9 + kKappa + 3;  // 20

}  // namespace rast5d::cost
