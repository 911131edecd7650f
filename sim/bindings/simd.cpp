// Test-only: the explicit-SIMD batch sample tests (sampletest/simd_batch.h) beside the scalar
// batch kernels of sampletest/kernels.h, on the same inputs, for the bit-equality test.
#include "bindings.h"

#include <algorithm>
#include <chrono>
#include <random>
#include <vector>

#include "sampletest/simd_batch.h"

namespace rast5d::bindings {

void register_simd(py::module_& m) {
  m.def("simd_isa", []() { return std::string(simd::isa()); },
        "The instruction set of the fused SIMD sample tests in this build: 'avx512', 'avx2' or 'scalar'.");
  m.def(
      "simd_batch_compare",
      [](int cls, const FArr& tri, const FArr& samples, bool back_face_cull) {
        require_shape(tri, {28}, "tri");
        require_shape(samples, {-1, 5}, "samples");
        if (cls != 2 && cls != 3) throw std::invalid_argument("cls: expected 2 (4D) or 3 (5D)");
        const float* q = tri.data();
        const BatchTri T{q[0],  q[1],  q[2],  q[3],  q[4],  q[5],  q[6],  q[7],  q[8],  q[9],
                         q[10], q[11], q[12], q[13], q[14], q[15], q[16], q[17], q[18], q[19],
                         q[20], q[21], q[22], q[23], q[24], q[25], q[26], q[27]};
        const int n = static_cast<int>(samples.shape(0));
        std::vector<float> x(n), y(n), u(n), v(n), t(n);
        for (int i = 0; i < n; ++i) {
          const float* s = samples.data() + 5 * i;
          x[i] = s[0], y[i] = s[1], u[i] = s[2], v[i] = s[3], t[i] = s[4];
        }
        py::array_t<float> es({2, 4, n});  // [scalar, simd][e0, e1, e2, det][i]
        py::array_t<std::uint8_t> fl({2, n});
        float* e = es.mutable_data();
        std::uint8_t* f = fl.mutable_data();
        const std::size_t N = static_cast<std::size_t>(n);
        if (cls == 2) {
          batch_edges_4d(n, T, x.data(), y.data(), u.data(), v.data(), e, e + N, e + 2 * N, e + 3 * N);
          simd::batch_test_4d(n, T, x.data(), y.data(), u.data(), v.data(), e + 4 * N, e + 5 * N, e + 6 * N,
                              e + 7 * N, back_face_cull, f + N);
        } else {
          batch_edges_5d(n, T, x.data(), y.data(), u.data(), v.data(), t.data(), e, e + N, e + 2 * N, e + 3 * N);
          simd::batch_test_5d(n, T, x.data(), y.data(), u.data(), v.data(), t.data(), e + 4 * N, e + 5 * N,
                              e + 6 * N, e + 7 * N, back_face_cull, f + N);
        }
        batch_flags(n, e, e + N, e + 2 * N, e + 3 * N, back_face_cull, f);
        return py::make_tuple(es, fl);
      },
      py::arg("cls"), py::arg("tri"), py::arg("samples"), py::arg("back_face_cull") = false,
      "Test only: ((2, 4, n) float32 [scalar, simd] x [e0, e1, e2, det], (2, n) uint8 flags) of the scalar "
      "batch kernels and the fused SIMD kernel (cls 2 = 4D, 3 = 5D) on samples (n, 5) = x, y, u, v, t; tri is "
      "BatchTri's 28 floats.");

  m.def(
      "simd_batch_bench",
      [](int cls, int n, int reps) {
        if (cls != 2 && cls != 3) throw std::invalid_argument("cls: expected 2 (4D) or 3 (5D)");
        if (n < 1 || n > (1 << 20) || reps < 1) throw std::invalid_argument("n, reps: expected 1..2^20, >= 1");
        std::mt19937 g(7);
        std::uniform_real_distribution<float> U(-1.0f, 1.0f);
        BatchTri T{};
        float* q = &T.X0;
        for (int k = 0; k < 28; ++k) q[k] = 8.0f * U(g);
        T.W0 = T.W1 = T.W2 = 2.0f;
        std::vector<float> x(n), y(n), u(n), v(n), t(n), e(4 * static_cast<std::size_t>(n));
        std::vector<std::uint8_t> f(static_cast<std::size_t>(n) + 16);
        for (int i = 0; i < n; ++i) x[i] = 8 * U(g), y[i] = 8 * U(g), u[i] = U(g), v[i] = U(g), t[i] = 0.5f + 0.5f * U(g);
        const std::size_t N = static_cast<std::size_t>(n);
        using clk = std::chrono::steady_clock;
        double best_scalar = 1e30, best_simd = 1e30;
        unsigned sink = 0;
        for (int r = 0; r < reps; ++r) {  // interleaved: scalar pass, fused pass; minima kept
          auto t0 = clk::now();
          if (cls == 2)
            batch_edges_4d(n, T, x.data(), y.data(), u.data(), v.data(), e.data(), e.data() + N, e.data() + 2 * N,
                           e.data() + 3 * N);
          else
            batch_edges_5d(n, T, x.data(), y.data(), u.data(), v.data(), t.data(), e.data(), e.data() + N,
                           e.data() + 2 * N, e.data() + 3 * N);
          batch_flags(n, e.data(), e.data() + N, e.data() + 2 * N, e.data() + 3 * N, false, f.data());
          auto t1 = clk::now();
          sink += f[static_cast<std::size_t>(r) % N];
          if (cls == 2)
            simd::batch_test_4d(n, T, x.data(), y.data(), u.data(), v.data(), e.data(), e.data() + N,
                                e.data() + 2 * N, e.data() + 3 * N, false, f.data());
          else
            simd::batch_test_5d(n, T, x.data(), y.data(), u.data(), v.data(), t.data(), e.data(), e.data() + N,
                                e.data() + 2 * N, e.data() + 3 * N, false, f.data());
          auto t2 = clk::now();
          sink += f[static_cast<std::size_t>(r) % N];
          best_scalar = std::min(best_scalar, std::chrono::duration<double>(t1 - t0).count());
          best_simd = std::min(best_simd, std::chrono::duration<double>(t2 - t1).count());
        }
        return py::make_tuple(n / best_scalar, n / best_simd, sink);
      },
      py::arg("cls"), py::arg("n") = 1024, py::arg("reps") = 2000,
      "Benchmark: (scalar tests/s, fused SIMD tests/s, checksum) of the batch sample-test kernels alone on "
      "one thread (cls 2 = 4D, 3 = 5D; n samples per batch, the minimum over reps interleaved passes).");
}

}  // namespace rast5d::bindings
