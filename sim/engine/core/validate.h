// The checks of the render parameters that need no sample table and no algorithm registry: every
// numeric parameter against its params.def domain, and what one params.def row cannot say (image
// and bin sizes, time strata, cache geometries, the depth buffer's compression). Shared by the frame
// (frame/render.cpp) and conservative rasterization.
#pragma once

#include <stdexcept>
#include <string>

#include "core/params.h"

namespace rast5d {

// Throws std::invalid_argument naming the parameter and its value.
inline void validate_frame_params(const RenderParams& p) {
  auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  auto str = [](auto v) { return std::to_string(v); };
  validate_domains(p);  // every numeric parameter against its params.def domain
  if (p.bin_size % 8 != 0) fail("bin_size: expected a multiple of 8, got " + str(p.bin_size));
  if (p.time_strata % p.time_splits != 0)  // each time stratum lies in one sub-interval
    fail("time_strata: expected a multiple of time_splits, got " + str(p.time_splits) + " / " + str(p.time_strata));
  // The texture cache's line size is a power of two and its lines fill whole sets.
  const int lb = p.tex_cache_line_bytes;
  if (lb & (lb - 1)) fail("tex_cache_line_bytes: expected a power of two, got " + str(lb));
  if (p.tex_cache_size_bytes % lb) fail("tex_cache_size_bytes: expected a multiple of the line size, got " + str(p.tex_cache_size_bytes));
  if (p.tex_cache_ways && (p.tex_cache_size_bytes / lb) % p.tex_cache_ways)
    fail("tex_cache_ways: expected 0 or a divisor of the number of lines, got " + str(p.tex_cache_ways));
  // The depth and colour tile caches (memory/sample_buffers.h): whole sets of whole lines.
  const int dl = p.depth_buffer_line_bytes;
  if (dl & (dl - 1)) fail("depth_buffer_line_bytes: expected a power of two, got " + str(dl));
  const long long dset = static_cast<long long>(dl) * (p.depth_buffer_cache_ways ? p.depth_buffer_cache_ways : 1);
  if (p.depth_buffer_cache_bytes % dset)
    fail("depth_buffer_cache_bytes: " + str(p.depth_buffer_cache_bytes) + " is not a whole number of sets of " +
         str(p.depth_buffer_cache_ways) + " x " + str(dl) + "-byte lines");
  const long long cl = static_cast<long long>(dl / 4) * p.color_buffer_bytes_per_sample;  // a colour line
  const long long cset = cl * (p.color_buffer_cache_ways ? p.color_buffer_cache_ways : 1);
  if (p.color_buffer_cache_bytes % cset)
    fail("color_buffer_cache_bytes: " + str(p.color_buffer_cache_bytes) + " is not a whole number of sets of " +
         str(p.color_buffer_cache_ways) + " x " + str(cl) + "-byte lines (" + str(dl / 4) + " samples of " +
         str(p.color_buffer_bytes_per_sample) + " bytes)");
  // Compression packs depth-buffer lines: without the depth-tile cache there are none to pack.
  if (p.depth_buffer_compression != DepthCompression::kNone && !p.depth_buffer_enabled)
    fail("depth_buffer_compression: '" + std::string(choice_name(p.depth_buffer_compression)) +
         "' compresses the depth-tile cache's lines, and depth_buffer_enabled is false (every sample goes to "
         "DRAM uncompressed): set compression 'none' or enable the depth buffer");
}

}  // namespace rast5d
