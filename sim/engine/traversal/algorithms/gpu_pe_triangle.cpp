// GPU_PE_TRIANGLE: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [Toth 2008] §4.5 parallel-edge bounding triangle bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuPETriangle = gpu::GpuBounding<A, gpu::Method::kPETriangle>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_pe_triangle",
                          "[Toth 2008] §4.5 parallel-edge bounding triangle (2D; 3 vertices, 1 triangle), rasterized, then a pixel-shader stochastic test of every sample of each fragment",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuPETriangle);

}  // namespace rast5d
