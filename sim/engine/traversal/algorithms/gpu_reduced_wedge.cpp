// GPU_REDUCED_WEDGE: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [Toth 2008] §4.5 reduced bounding wedge bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuReducedWedge = gpu::GpuBounding<A, gpu::Method::kReducedWedge>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_reduced_wedge",
                          "[Toth 2008] §4.5 reduced bounding wedge (the wedge's silhouette as one strip; the full wedge when the volume reaches the near plane), pixel-shader stochastic test",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuReducedWedge);

}  // namespace rast5d
