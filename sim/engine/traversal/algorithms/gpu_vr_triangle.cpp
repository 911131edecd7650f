// GPU_VR_TRIANGLE: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [Toth 2008] §4.6 variable-radius bounding triangle bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuVRTriangle = gpu::GpuBounding<A, gpu::Method::kVRTriangle>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_vr_triangle",
                          "[Toth 2008] §4.6 variable-radius bounding triangle (2D; tangent to the confusion circles; falls back to the parallel-edge triangle), pixel-shader stochastic test",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuVRTriangle);

}  // namespace rast5d
