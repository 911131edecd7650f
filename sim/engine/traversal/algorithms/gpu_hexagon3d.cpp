// GPU_HEXAGON3D: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [Toth 2008] §4.4 3D hexagonal bounding volume bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuHexagon3D = gpu::GpuBounding<A, gpu::Method::kHexagon3D>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_hexagon3d",
                          "[Toth 2008] §4.4 3D hexagonal bounding volume (12 vertices, 20 triangles), rasterized, pixel-shader stochastic test",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuHexagon3D);

}  // namespace rast5d
