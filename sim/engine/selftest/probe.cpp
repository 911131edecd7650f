#include "selftest/probe.h"

#include "sampletest/inside.h"
#include "setup/setup.h"

namespace rast5d {

ProbeResult probe_samples(const RenderParams& p, const float v0[9], const float v1[9],
                          const float* points, int m, bool force_general) {
  ProbeResult r;
  r.covered.assign(m, 0);
  r.hit.assign(m, 0);
  r.depth.assign(m, 0.0f);
  r.w_hit.assign(m, 0.0f);
  const FrameConst fc = make_frame_const(p);
  const float col[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};
  TriSetup tri;
  Counters c;
  setup_triangle<FastArith>(v0, v1, col, 0, p, fc, tri, c);
  if (c[Counter::setup_culled_near]) {
    r.dim_class = -1;
    return r;
  }
  // Off-screen or back-face culling in setup only affects bounds; the probe evaluates the kernel.
  const DimClass cls = force_general ? DimClass::k5D : tri.cls;
  r.dim_class = static_cast<int>(tri.cls);
  for (int i = 0; i < m; ++i) {
    const float* q = points + 5 * static_cast<std::size_t>(i);
    float X[3], Y[3], W[3], e[3], det;
    int n_ties;
    const bool covered = inside_test<float>(tri, cls, fc, q[0], q[1], q[2], q[3], q[4],
                                            p.backface_cull, X, Y, W, e, det, n_ties);
    if (!covered) continue;
    r.covered[i] = 1;
    float sum, z;
    const bool front = hit_depth<float>(e, det, fc.neg_near, sum, z);
    r.hit[i] = front ? 1 : 0;
    r.depth[i] = z;
    r.w_hit[i] = det / sum;
  }
  return r;
}

}  // namespace rast5d
