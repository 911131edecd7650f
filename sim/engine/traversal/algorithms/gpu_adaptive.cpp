// GPU_ADAPTIVE: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [Toth 2008] §4.7 per-triangle choice: parallel-edge triangle for small blur bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuAdaptive = gpu::GpuBounding<A, gpu::Method::kAdaptive>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_adaptive",
                          "[Toth 2008] §4.7 per-triangle choice: parallel-edge triangle for small blur, 2D hexagon for large, 3D hexagon across the near plane, convex hull when moving; pixel-shader stochastic test",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuAdaptive);

}  // namespace rast5d
