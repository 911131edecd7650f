// Observers of one worker's traversal (docs/architecture.md): the memory model's tile caches, the
// timing recorder and per-pixel statistics watch the stream of visits a traversal makes, while the
// traversal algorithms know only SamplePipeline (traversal/sample_pipeline.h), which dispatches.
//
// Events, for every screen bin a worker takes (frame/traverse.cpp and the sample pipeline):
//   begin_bin  { begin_triangle  { target* end_visit* }  end_triangle }*  begin_tail  end_bin
// end_visit() follows the visit's samples (tested, depth-tested, shaded); target() announces that
// the work from now on is done for the pixels [x0, x1) x [y0, y1) (only to observers that ask for
// targets); begin_tail() precedes the bin's end-of-bin work (the line samples' composite), end_bin()
// follows it. An observer sees the events of the bins its thread takes, in that thread's order, so
// anything it accumulates per bin does not depend on the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "core/bin_rect.h"

namespace rast5d {

class VisitObserver {
 public:
  virtual ~VisitObserver() = default;
  // Which events the observer needs: visit ends make the traversal close every visit (and test each
  // visit's samples before the next one starts); targets make it announce pixel rectangles.
  virtual bool wants_visits() const { return false; }
  virtual bool wants_targets() const { return false; }

  virtual void begin_bin(int /*bin*/, const BinRect& /*rect*/) {}
  // The triangle's pixels in this bin, [x0, x1) x [y0, y1); home: the bin that charges its setup.
  virtual void begin_triangle(std::uint32_t /*tri*/, int /*x0*/, int /*y0*/, int /*x1*/, int /*y1*/, bool /*home*/) {}
  virtual void target(int /*x0*/, int /*y0*/, int /*x1*/, int /*y1*/, int /*kind*/) {}
  // Whether the current target is already [x0, x1) x [y0, y1) (then target() would change nothing).
  virtual bool aims_at(int /*x0*/, int /*y0*/, int /*x1*/, int /*y1*/) const { return true; }
  virtual void end_visit() {}
  virtual void end_triangle() {}
  virtual void begin_tail() {}
  virtual void end_bin() {}
  // Pixel trace (the counting path): whether pixel (px, py) is traced, and each of its samples.
  virtual bool traces(int /*px*/, int /*py*/) const { return false; }
  virtual void traced_sample(std::int64_t /*tri*/, int /*s*/, bool /*covered*/, bool /*hit*/) {}
};

// The observers of one worker, in dispatch order (the memory model before the timing recorder,
// which reads what the memory model added at the same event).
class Observers final : public VisitObserver {
 public:
  void add(VisitObserver* o) {
    list_.push_back(o);
    visits_ = visits_ || o->wants_visits();
    targets_ = targets_ || o->wants_targets();
  }
  bool empty() const { return list_.empty(); }
  bool wants_visits() const override { return visits_; }
  bool wants_targets() const override { return targets_; }

  void begin_bin(int bin, const BinRect& r) override {
    for (auto* o : list_) o->begin_bin(bin, r);
  }
  void begin_triangle(std::uint32_t tri, int x0, int y0, int x1, int y1, bool home) override {
    for (auto* o : list_) o->begin_triangle(tri, x0, y0, x1, y1, home);
  }
  void target(int x0, int y0, int x1, int y1, int kind) override {
    for (auto* o : list_)
      if (o->wants_targets()) o->target(x0, y0, x1, y1, kind);
  }
  bool aims_at(int x0, int y0, int x1, int y1) const override {
    for (auto* o : list_)
      if (o->wants_targets() && !o->aims_at(x0, y0, x1, y1)) return false;
    return true;
  }
  void end_visit() override {
    for (auto* o : list_) o->end_visit();
  }
  void end_triangle() override {
    for (auto* o : list_) o->end_triangle();
  }
  void begin_tail() override {
    for (auto* o : list_) o->begin_tail();
  }
  void end_bin() override {
    for (auto* o : list_) o->end_bin();
  }
  bool traces(int px, int py) const override {
    for (auto* o : list_)
      if (o->traces(px, py)) return true;
    return false;
  }
  void traced_sample(std::int64_t tri, int s, bool covered, bool hit) override {
    for (auto* o : list_) o->traced_sample(tri, s, covered, hit);
  }

 private:
  std::vector<VisitObserver*> list_;
  bool visits_ = false, targets_ = false;
};

}  // namespace rast5d
