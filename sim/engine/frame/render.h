// The frame: one render, read as its stages (frame/render.cpp):
//   set-up (frame/setup_stage.cpp)  triangle set-up on every thread, or of the sampled bins' triangles
//   binning (frame/binning.h)       each screen bin lists the triangles overlapping it
//   traversal (frame/traverse.cpp)  worker threads take whole bins; each runs the algorithm with its
//                                   observers (memory model, timing recorder, per-pixel statistics)
//   the bin stream (frame/bin_stream.h)  completed bins, in bin order: the texture-cache replay and
//                                   the timing model consume them as they come
//   resolve and assembly            each bin resolves into the image as it completes; the counters,
//                                   the timing result and the sampled bins' rows are assembled here
//
// Contract: the image, the per-sample depths, the counters and the timing figures do not depend on
// the thread count (bins are owned by one thread at a time, triangles reach a bin in submission
// order, and the stream consumes bins in bin order).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/counters.h"
#include "core/params.h"
#include "core/pixel_stats.h"
#include "core/sample_table.h"
#include "core/scene.h"
#include "memory/sample_buffers.h"
#include "sampled/sampled_setup.h"
#include "timing/timing.h"

namespace rast5d {

struct RenderResult {
  std::vector<float> image;  // height x width x 3, linear, row 0 at the top
  Counters counters;
  bool interrupted = false;
  // Per-sample depth (z = 1 - near / W, +inf where empty) and winning triangle index (-1 where
  // empty), height x width x spp; filled only when requested.
  std::vector<float> sample_depth;
  std::vector<std::int32_t> sample_triangle;
  // With a bin list or pipeline.sample_fraction < 1: the traversed bins and what the estimator needs.
  SampledBins sampled;
  // The timing and memory model (p.record_timing): its result, the memory model's totals (which
  // buffers it covered), and the work records when kept (RenderOptions::keep_timing_records): one per
  // culled triangle (setup only, bin -1), then per screen bin in raster order its records.
  bool timed = false;
  TimingResult timing;
  bool memory_depth = false, memory_color = false;
  memory::MemoryTotals memory;
  std::vector<TileWork> timing_records;
  // Pixel trace (PixelStats::tracing()): the events and samples of the traced pixel, in order.
  std::vector<TraceEvent> trace_events;
  std::vector<TraceSample> trace_samples;
};

// What a render is asked for besides the image and the counters.
struct RenderOptions {
  bool export_samples = false;
  // Render only these screen bins (row-major indices, distinct, in range) and return each one's
  // counters in RenderResult::sampled; the other bins stay empty.
  const std::vector<int>* bins = nullptr;
  // Per-pixel counter maps (core/pixel_stats.h), filled in place; in trace mode only the traced
  // pixel's bin is rasterized.
  PixelStats* pixel_stats = nullptr;
  // Called from the calling thread with the screen bins finished so far, every few milliseconds.
  std::function<void(int, int)> progress;
  // The timing model's units (p.record_timing: default units when null).
  const TimingConfig* timing = nullptr;
  bool keep_timing_records = false;
};

// Throws std::invalid_argument for bad parameters. `interrupted` is polled from the calling
// thread every few milliseconds while workers run; when it returns true the render stops and
// RenderResult::interrupted is set.
RenderResult render(const RenderParams& p, const SceneArrays& scene, const SampleTable& table,
                    const std::function<bool()>& interrupted, const RenderOptions& options = {});

// The checks of p against the algorithm registry and the sample table (frame/validate.cpp); the
// rest are validate_frame_params (core/validate.h).
void validate_params(const RenderParams& p, const SampleTable& table);

// The registry's facts about every traversal algorithm: its name and description, whether it needs
// an interleaved table, the samples it tests ("points" or "lines"), the sample tables it accepts
// ("points": any point table, "interleaved": point tables with discrete lens coordinates, "lines": line
// tables), whether it runs the depth-cull stage (HiZ, occlusion queries) and its pipeline ("sample": the 5D
// sample pipeline, "gpu": a conventional GPU's).
struct AlgorithmEntry {
  std::string name, description;
  bool needs_interleaved_table;
  std::string samples, tables;
  bool depth_cull;
  std::string pipeline;
};
std::vector<AlgorithmEntry> algorithms();

}  // namespace rast5d
