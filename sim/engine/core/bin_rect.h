// A screen bin: the unit of work of one worker thread (traversal/render.cpp bins the screen; the
// bin's buffers, backend/bin_buffers.h and backend/hiz.h, cover exactly its pixels).
#pragma once

namespace rast5d {

struct BinRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // pixels [x0, x1) x [y0, y1)
};

}  // namespace rast5d
