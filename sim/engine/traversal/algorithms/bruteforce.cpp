// BRUTEFORCE ([Akenine-Möller 2012] §6): test every sample of every pixel inside the triangle's
// conservative screen bounds over the whole lens and shutter. No tile test. Shading visit
// (backend/shading.h): the whole triangle in the bin, since each pixel is walked once per triangle.
#include <algorithm>

#include "traversal/traversal.h"

namespace rast5d {
namespace {

template <class A>
class BruteForce final : public Traversal {
 public:
  BruteForce(const Frame& f, ThreadState& ts) : f_(f), pipe_(f, ts) {}

  void rasterize(const TriSetup& tri, const BinRect& bin, bool /*charge_setup*/) override {
    const int x0 = std::max(tri.bx0, bin.x0), x1 = std::min(tri.bx1, bin.x1);
    const int y0 = std::max(tri.by0, bin.y0), y1 = std::min(tri.by1, bin.y1);
    pipe_.begin(tri);
    for (int py = y0; py < y1; ++py)
      for (int px = x0; px < x1; ++px) pipe_.push_pixel(px, py, f_.table.pixel(px, py));
    pipe_.end_visit();  // a visit = the triangle's pixels in this bin, each walked once
    pipe_.flush();
  }

 private:
  const Frame& f_;
  SamplePipeline<A> pipe_;
};

}  // namespace

RAST5D_REGISTER_TRAVERSAL("bruteforce",
                          "Test every sample in the triangle's screen bounds over the whole lens "
                          "and shutter ([Akenine-Möller 2012] §6)",
                          TableKinds::kPoints, PipelineKind::kSample, BruteForce);

}  // namespace rast5d
