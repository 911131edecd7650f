#include "frame/setup_stage.h"

#include <stdexcept>
#include <string>
#include <thread>

#include "backend/texture.h"
#include "setup/setup.h"

namespace rast5d {

namespace {

bool set_up(const SceneArrays& scene, int i, const RenderParams& p, const FrameConst& fc, TriSetup& out, Counters& c) {
  const float* v0 = scene.v0 + static_cast<std::size_t>(i) * 9;
  const float* v1 = scene.v1 + static_cast<std::size_t>(i) * 9;
  const float* col = scene.colors + static_cast<std::size_t>(i) * 9;
  const bool alive = p.op_count == OpCount::kExact
                         ? setup_triangle<ExactArith>(v0, v1, col, static_cast<std::uint32_t>(i), p, fc, out, c)
                         : setup_triangle<FastArith>(v0, v1, col, static_cast<std::uint32_t>(i), p, fc, out, c);
  if (scene.alpha) out.alpha = scene.alpha[i];
  return alive;
}

}  // namespace

FrameSetup setup_stage(const RenderParams& p, const FrameConst& fc, const SceneArrays& scene, int spp, int n_threads,
                       const std::vector<int>* bins, PixelStats* pstats, SampledBins& sampled) {
  FrameSetup fs;
  fs.restricted = (bins || p.sample_fraction < 1.0) && !pstats && !p.record_timing;
  const std::size_t n = static_cast<std::size_t>(scene.n);
  if (!fs.restricted) fs.setups.resize(n);
  fs.S = fs.restricted ? fs.sparse.allocate(n) : fs.setups.data();
  fs.alive.assign(n, 0);
  fs.counters.assign(static_cast<std::size_t>(n_threads), Counters{});
  if (fs.restricted) {
    sampled_setup(p, fc, scene, spp, bins, fs.S, fs.alive, fs.counters[0], fs.homed, fs.drawn, sampled, &fs.split);
  } else if (pstats) {  // per-pixel statistics: one thread, each triangle's setup charged to its bounds
    PixelCursor cur;
    cur.attach(pstats);
    for (int i = 0; i < scene.n; ++i) {
      fs.alive[i] = set_up(scene, i, p, fc, fs.S[i], fs.counters[0]);
      const TriSetup& t = fs.S[i];
      cur.triangle = i;
      cur.x0 = t.bx0, cur.y0 = t.by0, cur.x1 = t.bx1, cur.y1 = t.by1, cur.kind = 3;
      cur.commit(fs.counters[0], true);
      cur.commit(fs.counters[0], false);
    }
    fs.frame_pool = cur.frame_pool;
    fs.trace_events = std::move(cur.events);
  } else {  // static partition over triangles, each thread its own counters
    auto work = [&](int t) {
      const int lo = static_cast<int>(static_cast<long long>(scene.n) * t / n_threads);
      const int hi = static_cast<int>(static_cast<long long>(scene.n) * (t + 1) / n_threads);
      for (int i = lo; i < hi; ++i) fs.alive[i] = set_up(scene, i, p, fc, fs.S[i], fs.counters[t]);
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < n_threads; ++t) pool.emplace_back(work, t);
    work(0);
    for (auto& th : pool) th.join();
  }
  fs.live.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    if (fs.alive[i]) fs.live.push_back(static_cast<std::uint32_t>(i));
  return fs;
}

// The per-render shading constants: textures with mip chains and addresses, per-triangle texture
// slots, uvs, analytic uv derivatives and levels of detail (backend/texture.h).
void build_shade_frame(const RenderParams& p, const SceneArrays& scene, const TriSetup* setups,
                       const std::vector<char>& alive, int n_bins, ShadeFrame& sf) {
  sf.mode = p.shading;
  sf.grid = p.shading_grid;
  sf.cache_entries = p.shading_cache_entries;
  sf.filter = p.texture_filter;
  sf.line_bytes = p.tex_cache_line_bytes;
  const bool have_tex = scene.uvs && scene.tex_slots && !scene.textures.empty();
  sf.texture_count = have_tex ? p.texture_count : 0;
  sf.sample_dist_tex = !scene.textures.empty() ? p.texture_sample_distribution_index : -1;
  if (sf.sample_dist_tex >= static_cast<int>(scene.textures.size()))
    throw std::invalid_argument("texture_sample_distribution_index: no texture " +
                                std::to_string(sf.sample_dist_tex));
  if (!sf.textured()) return;
  for (const auto& t : scene.textures) sf.textures.add(t.data, t.height, t.width, t.channels);
  sf.textures.layout(p.texture_layout);
  if (sf.mode != ShadingMode::kNone) sf.streams.assign(static_cast<std::size_t>(n_bins), {});
  if (sf.texture_count == 0) return;
  const std::size_t n = static_cast<std::size_t>(scene.n);
  sf.uvs.assign(scene.uvs, scene.uvs + n * 6);
  sf.tex_ids.assign(scene.tex_slots, scene.tex_slots + n * kMaxTexSlots);
  for (std::size_t i = 0; i < sf.tex_ids.size(); ++i) {
    std::int32_t& id = sf.tex_ids[i];
    if (static_cast<int>(i % kMaxTexSlots) >= sf.texture_count) {
      id = -1;
    } else if (id < -1 || id >= sf.textures.size()) {
      throw std::invalid_argument("tex_slots: triangle " + std::to_string(i / kMaxTexSlots) + " uses texture " +
                                  std::to_string(id) + ", expected -1.." + std::to_string(sf.textures.size() - 1));
    }
  }
  sf.jac.assign(n * 4, 0.0);
  sf.lod.assign(n * kMaxTexSlots, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    if (!alive[i]) continue;
    const TriSetup& t = setups[i];
    uv_jacobian(t.X, t.Y, t.W, &sf.uvs[i * 6], p.near_w, &sf.jac[i * 4]);
    for (int k = 0; k < kMaxTexSlots; ++k) {
      const int id = sf.tex_ids[i * kMaxTexSlots + k];
      if (id >= 0) {
        const MipLevel& l0 = sf.textures[id].levels[0];
        sf.lod[i * kMaxTexSlots + k] = lod_from_jacobian(&sf.jac[i * 4], l0.w, l0.h);
      }
    }
  }
}

}  // namespace rast5d
