// GPU_WEDGE: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [Toth 2008] §4.5 bounding wedge bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuWedge = gpu::GpuBounding<A, gpu::Method::kWedge>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_wedge",
                          "[Toth 2008] §4.5 bounding wedge (3D; 6 vertices, 8 triangles), rasterized, pixel-shader stochastic test",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuWedge);

}  // namespace rast5d
