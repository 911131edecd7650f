// Traversal algorithms: one interface, one file per implementation, registered by name
// (Ramulator 2's self-registering factory; docs/architecture.md). Adding an algorithm = one .cpp file in
// traversal/algorithms/ (or a folder there, like tile/) with a RAST5D_REGISTER_TRAVERSAL line.
//
// Calling protocol (one instance per worker thread, created once per render):
//   1. The engine runs triangle setup (setup/setup.h) for every triangle, once.
//   2. For each screen bin, in any order across threads, and for each triangle whose bounds
//      overlap the bin, in submission order, the engine calls rasterize(tri, bin, charge_setup).
//      charge_setup is true in exactly one bin per triangle (its first bin in raster order): an
//      algorithm recomputes its per-triangle setup in every bin it is called for, but charges the
//      operations only then, so counts never depend on binning or thread count.
//   3. rasterize() hands candidate samples of pixels inside the bin to the SamplePipeline
//      (traversal/sample_pipeline.h), which runs the exact sample test and the backend.
//
// Contract: an implementation must be *exact*: it must pass to the sample pipeline every sample
// of the bin that the exact sample test hits (it may pass more: that is its inefficiency), each
// at most once per call, for every triangle class (moving triangles through a conservative path,
// counted in trav.motion_fallback). Tile tests it uses must be conservative (never cull a hit).
// Then all algorithms render bit-identical images from the same sample table and differ only in
// their work counters.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "core/bin_rect.h"
#include "setup/setup.h"
#include "traversal/sample_pipeline.h"

namespace rast5d {

class Traversal {
 public:
  virtual ~Traversal() = default;
  virtual void rasterize(const TriSetup& tri, const BinRect& bin, bool charge_setup) = 0;
  // Called once per bin after its last triangle, before the bin is resolved (every bin, also those
  // no triangle reached). Algorithms that defer work to the end of a bin (line samples' composite)
  // do it here.
  virtual void end_bin(const BinRect& /*bin*/) {}
};

// A traversal that runs the depth-cull stage (backend/zcull.h), which answers occlusion queries,
// declares `static constexpr bool kDepthCull = true;`.
template <class T>
constexpr bool runs_depth_cull() {
  if constexpr (requires { T::kDepthCull; })
    return T::kDepthCull;
  else
    return false;
}

// The sample tables an algorithm accepts: any point-sample table, only point tables with discrete
// lens coordinates (SampleTable.interleaved, accumulation), or only line-sample tables
// (SampleTable.lines). The sample kind (point or line samples) follows from it.
enum class TableKinds { kPoints, kInterleaved, kLines };
// The pipeline an algorithm's samples go through: the 5D sample pipeline (traversal/sample_pipeline.h)
// or a conventional GPU's (gpu/gpu_pipeline.h: geometry shader, 2D raster, pixel-shader sample test).
enum class PipelineKind { kSample, kGpu };

struct TraversalInfo {
  std::string description;
  bool needs_interleaved_table = false;  // tables == kInterleaved
  bool depth_cull = false;  // answers occlusion queries and reads HiZ (runs_depth_cull)
  std::function<std::unique_ptr<Traversal>(const Frame&, ThreadState&, bool exact)> create;
  TableKinds tables = TableKinds::kPoints;
  PipelineKind pipeline = PipelineKind::kSample;
  bool line_samples() const { return tables == TableKinds::kLines; }
};

class TraversalRegistry {
 public:
  static std::map<std::string, TraversalInfo>& entries() {
    static std::map<std::string, TraversalInfo> m;
    return m;
  }
  static bool add(const std::string& name, TraversalInfo info) {
    entries().emplace(name, std::move(info));
    return true;
  }
};

#define RAST5D_REGISTER_TRAVERSAL(NAME, DESCRIPTION, TABLES, PIPELINE, CLASS)                   \
  static const bool kRegistered_##CLASS = ::rast5d::TraversalRegistry::add(                       \
      NAME, ::rast5d::TraversalInfo{                                                              \
                DESCRIPTION, (TABLES) == ::rast5d::TableKinds::kInterleaved,                      \
                ::rast5d::runs_depth_cull<CLASS<::rast5d::FastArith>>(),                          \
                [](const ::rast5d::Frame& f, ::rast5d::ThreadState& ts,                           \
                   bool exact) -> std::unique_ptr<::rast5d::Traversal> {                          \
                  if (exact) return std::make_unique<CLASS<::rast5d::ExactArith>>(f, ts);         \
                  return std::make_unique<CLASS<::rast5d::FastArith>>(f, ts);                     \
                },                                                                                \
                (TABLES), (PIPELINE)})

}  // namespace rast5d
