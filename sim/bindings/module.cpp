// sim._core: the pybind11 face of the engine. The Python layer (sim/*.py) validates user input and
// converts scenes and cameras into these arrays; see sim/_core.pyi for the documented signatures.
// Each binding file registers one stage's functions.
#include "bindings.h"

PYBIND11_MODULE(_core, m) {
  m.doc() = "rast5d engine: a functional, operation-counting 5D stochastic rasterizer";
  using namespace rast5d::bindings;
  register_params(m);
  register_render(m);
  register_timing(m);
  register_conservative(m);
  register_selftest(m);
  register_gpu(m);
  register_simd(m);
}
