// The frame's set-up stage (frame/render.h): every triangle set up once (threads take static slices;
// with per-pixel statistics one thread charges each triangle's set-up to its bounds), or, for a bin
// list or sampled simulation, only the triangles that reach the drawn bins (sampled/sampled_setup.h);
// then the per-render shading constants (textures, uvs, levels of detail).
#pragma once

#include <cstdint>
#include <vector>

#include "backend/shading.h"
#include "core/counters.h"
#include "core/params.h"
#include "core/pixel_stats.h"
#include "core/scene.h"
#include "core/triangle.h"
#include "sampled/sampled_setup.h"

namespace rast5d {

struct FrameSetup {
  std::vector<TriSetup> setups;   // every triangle's (a whole-frame render)
  UnconstructedSetups sparse;     // restricted renders: only the set-up triangles' slots
  TriSetup* S = nullptr;          // the set-ups, either way
  std::vector<char> alive;        // per triangle: set up and not culled
  std::vector<std::uint32_t> live;  // the alive triangles, in submission order
  std::vector<Counters> counters;   // per thread
  bool restricted = false;          // only the drawn bins' triangles were set up
  std::vector<int> drawn;           // restricted: the bins to traverse (with split: the drawn units)
  SplitDraw split;                  // pipeline.sample_split: each drawn unit's screen bin and triangles
  std::vector<Counters> homed;      // restricted: setup counters of the triangles homed in drawn bin k
  std::vector<std::uint64_t> frame_pool;  // per-pixel statistics: set-up work with no pixel bounds
  std::vector<TraceEvent> trace_events;   // pixel trace: the set-up events of the traced pixel
};

// Restricted when a bin list or sampled simulation asks for part of the frame and nothing needs the
// whole frame (per-pixel statistics, the timing model).
FrameSetup setup_stage(const RenderParams& p, const FrameConst& fc, const SceneArrays& scene, int spp, int n_threads,
                       const std::vector<int>* bins, PixelStats* pixel_stats, SampledBins& sampled);

void build_shade_frame(const RenderParams& p, const SceneArrays& scene, const TriSetup* setups,
                       const std::vector<char>& alive, int n_bins, ShadeFrame& sf);

}  // namespace rast5d
