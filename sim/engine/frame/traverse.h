// The frame's traversal stage (frame/render.h): worker threads take whole screen bins in order and
// run the algorithm over each bin's triangles, with their observers: the memory model's tile caches
// (memory/sample_buffers.h), the timing recorder (timing/recorder.h) and per-pixel statistics
// (core/pixel_stats.h). Each finished bin is resolved into the image and handed to the bin stream.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "backend/shading.h"
#include "core/pixel_stats.h"
#include "core/triangle.h"
#include "frame/bin_stream.h"
#include "frame/binning.h"
#include "frame/render.h"
#include "traversal/sample_pipeline.h"

namespace rast5d {

// One worker thread: its state and the observers of its traversal.
struct Worker {
  ThreadState ts;
  std::unique_ptr<memory::SampleBufferModel> memory;
  std::unique_ptr<TimingRecorder> recorder;
  std::unique_ptr<PixelStatsObserver> pixels;
};

struct TraversalJob {
  const RenderParams& p;
  const Frame& frame;
  const TriSetup* setups;
  const Binning& binning;
  ShadeFrame& shade;
  const std::vector<int>* work;  // the bins to traverse (nullptr: every bin, in order)
  const SplitDraw* split;        // units of dense bins: item k's triangles (nullptr: whole bins)
  bool moving;                   // some live triangle moves
  const RenderOptions& options;
  const std::function<bool()>& interrupted;
};

// Workers for n_threads threads, their observers attached.
std::vector<std::unique_ptr<Worker>> make_workers(const TraversalJob& job, int n_threads);

// Run the workers over the job's bins; fills result's image, sample exports and per-bin counter rows,
// sets result.interrupted. Rethrows a worker's exception.
void traverse_bins(const TraversalJob& job, std::vector<std::unique_ptr<Worker>>& workers, BinStream& stream,
                   RenderResult& result);

}  // namespace rast5d
