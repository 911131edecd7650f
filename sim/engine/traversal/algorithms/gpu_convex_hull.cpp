// GPU_CONVEX_HULL: the conventional-GPU pipeline (traversal/algorithms/gpu_pipeline.h) with the [McGuire 2010] bound.
#include "traversal/algorithms/gpu_pipeline.h"

namespace rast5d {
namespace {

template <class A>
using GpuConvexHull = gpu::GpuBounding<A, gpu::Method::kConvexHull>;

}  // namespace

RAST5D_REGISTER_TRAVERSAL("gpu_convex_hull",
                          "[McGuire 2010] (2+1)D convex hull of the vertices' confusion boxes at both shutter ends (motion and defocus; clip-and-box across z = 0), pixel-shader stochastic test",
                          TableKinds::kPoints, PipelineKind::kGpu, GpuConvexHull);

}  // namespace rast5d
