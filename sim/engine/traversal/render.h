// The render orchestrator: setup -> binning -> per-bin traversal on worker threads -> resolve.
//
// Contract: the image, the per-sample depths and the counters do not depend on the thread count
// (bins are owned by one thread at a time and triangles reach a bin in submission order).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/counters.h"
#include "core/params.h"
#include "core/pixel_stats.h"
#include "core/sample_table.h"
#include "timing/timing.h"

namespace rast5d {

struct SceneArrays {
  int n = 0;
  const float* v0 = nullptr;      // n x 3 x 3: (X_h, Y_h, W) per vertex at t = 0
  const float* v1 = nullptr;      // same at t = 1
  const float* colors = nullptr;  // n x 3 x 3 linear RGB per vertex
  const float* alpha = nullptr;   // n opacities in [0, 1] (optional: stochastic transparency)
  // Texturing (optional): uvs n x 3 x 2; tex_slots n x 4 texture indices (-1 unused); textures.
  const float* uvs = nullptr;
  const std::int32_t* tex_slots = nullptr;
  struct TextureView {
    const float* data;
    int height, width, channels;
  };
  std::vector<TextureView> textures;
};

struct RenderResult {
  std::vector<float> image;  // height x width x 3, linear, row 0 at the top
  Counters counters;
  bool interrupted = false;
  // Per-sample depth (z = 1 - near / W, +inf where empty) and winning triangle index (-1 where
  // empty), height x width x spp; filled only when requested.
  std::vector<float> sample_depth;
  std::vector<std::int32_t> sample_triangle;
  // Timing model input (p.record_timing): one record per culled triangle (setup only, bin -1),
  // then per screen bin in raster order one record per (triangle, bin) visit in submission order.
  // Independent of the thread count.
  std::vector<TileWork> timing_records;
  // Sampled simulation (render(..., bins)): the rendered bins' counters, one row of kNumCounters
  // per entry of `bins` in its order: its traversal work and the setup of the live triangles homed in
  // it (traversal/sampled_setup.h; with pixel statistics or timing records, traversal work only);
  // `counters` holds the rows' sum plus the frame's exact part (setup.triangles, culled triangles).
  std::vector<std::uint64_t> bin_counters;
  // With a bin list or pipeline.sample_fraction < 1: every bin's brute-force work (sum over its
  // triangles of their bounds' pixels in the bin, times spp), the traversed bins (the list, or the
  // stratified draw of traversal/bin_sample.h), the stratum of each and the strata sizes (empty:
  // every bin with triangles was traversed).
  std::vector<std::int64_t> bin_work;
  std::vector<int> sampled_bins, sampled_stratum, strata_sizes;
  // With bin_work: kBinAux per bin, the regression estimator's auxiliary variables (coverage,
  // footprint and edge, samples; traversal/bin_covariates.h).
  std::vector<double> bin_aux;
  // Their frame totals (kBinAux): summed per triangle when only the drawn bins' auxiliaries are computed
  // (traversal/sampled_setup.h: bin_aux is then NaN in the other bins), else the sums of bin_aux.
  std::vector<double> bin_aux_total;
  // Pixel trace (PixelStats::tracing()): the events and samples of the traced pixel, in order.
  std::vector<TraceEvent> trace_events;
  std::vector<TraceSample> trace_samples;
};

// Optional observers of one render. pixel_stats: per-pixel counter maps (core/pixel_stats.h),
// filled in place; in trace mode only the traced pixel's bin is rasterized. progress(done, total)
// is called from the calling thread with the screen bins finished so far, every few milliseconds.
struct RenderObservers {
  PixelStats* pixel_stats = nullptr;
  std::function<void(int, int)> progress;
};

// Throws std::invalid_argument for bad parameters. `interrupted` is polled from the calling
// thread every few milliseconds while workers run; when it returns true the render stops and
// RenderResult::interrupted is set.
// bins (optional): render only these screen bins (row-major indices, distinct, in range) and
// return each one's counters in RenderResult::bin_counters; the other bins stay empty.
RenderResult render(const RenderParams& p, const SceneArrays& scene, const SampleTable& table,
                    const std::function<bool()>& interrupted, bool export_samples = false,
                    const std::vector<int>* bins = nullptr, const RenderObservers& observers = {});

void validate_params(const RenderParams& p, const SampleTable& table);
// The checks that need no sample table (image size, tile and bin sizes, intervals, shading...).
void validate_frame_params(const RenderParams& p);

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
