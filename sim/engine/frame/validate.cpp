// The checks of a render's parameters against the algorithm registry and the sample table.
#include <stdexcept>
#include <string>

#include "core/validate.h"
#include "frame/render.h"
#include "traversal/traversal.h"

namespace rast5d {

std::vector<AlgorithmEntry> algorithms() {
  std::vector<AlgorithmEntry> out;
  for (const auto& [name, info] : TraversalRegistry::entries())
    out.push_back({name, info.description, info.needs_interleaved_table, info.line_samples() ? "lines" : "points",
                   info.tables == TableKinds::kLines         ? "lines"
                   : info.tables == TableKinds::kInterleaved ? "interleaved"
                                                             : "points",
                   info.depth_cull, info.pipeline == PipelineKind::kGpu ? "gpu" : "sample"});
  return out;
}

void validate_params(const RenderParams& p, const SampleTable& table) {
  auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  validate_frame_params(p);
  const auto& reg = TraversalRegistry::entries();
  auto it = reg.find(p.algorithm);
  if (it == reg.end()) {
    std::string names;
    for (const auto& kv : reg) names += (names.empty() ? "" : ", ") + kv.first;
    fail("algorithm: unknown '" + p.algorithm + "' (known: " + names + ")");
  }
  if (it->second.needs_interleaved_table && table.n_lens() == 0)
    fail("algorithm: '" + p.algorithm +
         "' needs an interleaved sample table (SampleTable.interleaved), got a table without "
         "discrete lens coordinates");
  // Occlusion queries are answered by the depth-cull stage (backend/zcull.h); algorithms without it
  // would draw the query triangles as occluders.
  if (p.query_first >= 0 && p.query_mode != QueryMode::kNone && !it->second.depth_cull) {
    std::string names;
    for (const auto& kv : reg)
      if (kv.second.depth_cull) names += (names.empty() ? "'" : ", '") + kv.first + "'";
    fail("algorithm: occlusion queries are answered by the algorithms with a depth-cull stage (" + names + "); got '" +
         p.algorithm + "'");
  }
  const bool lines_algo = it->second.line_samples();
  const std::string quoted = "'" + p.algorithm + "'";
  if (lines_algo != p.table_lines)
    fail(lines_algo ? "algorithm: " + quoted + " tests line samples and needs a line-sample table (SampleTable.lines), "
                      "got a point-sample table"
                    : "algorithm: " + quoted +
                          " tests point samples, got a line-sample table (SampleTable.lines needs a line-sample "
                          "algorithm)");
  if (lines_algo && p.lens_shape != LensShape::kDisk)
    fail("lens_shape: line samples (algorithm " + quoted + ") cross the disk lens through its centre; got a non-disk lens");
  if (lines_algo && p.shading == ShadingMode::kPerLensCell)
    fail("shading: line samples have no lens-grid cells, so 'per_lens_cell' does not apply to algorithm " + quoted +
         "; use 'none', 'per_sample', 'msaa' or 'cache'");
  if (p.lens_grid != table.grid())
    fail("lens_grid: the sample table was bucketed for G=" + std::to_string(table.grid()) +
         ", got " + std::to_string(p.lens_grid));
}

}  // namespace rast5d
