// GPU_HEXAGON2D: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [Toth 2008] §4.4 2D bounding hexagon bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuHexagon2D = gpu::GpuBounding<A, gpu::Method::kHexagon2D>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_hexagon2d",
                          "[Toth 2008] §4.4 2D bounding hexagon (6 vertices, 4 triangles), rasterized, then a pixel-shader stochastic test of every sample of each fragment",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuHexagon2D);

}  // namespace rast5d
