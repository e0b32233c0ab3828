#include "bake/proxy_bake.h"

#include <string>
#include <utility>

#include "reduction/ghost.h"
#include "reduction/prolongation.h"
#include "util/bake_stages.h"
#include "util/errors.h"

namespace modal_deform {

Basis bake_on_proxy(const VerticesRef& V, const MovingPart& part, const BakeOptions& options,
                    Basis fine, Progress& progress) {
  Basis timed;  // the proxy stage's time, until the proxy's basis exists
  Progress as_proxy([&progress](const std::string&, double fraction) {
    progress.report(stages::kProxy, fraction);
    return true;
  });
  const Ghost proxy = BakeRun{options, timed, progress}.stage(stages::kProxy, [&] {
    return ghost_mesh(part.V, part.F, part.mass, options.proxy, &as_proxy, part.sides());
  });
  // The proxy's elements carry the fine paint's means (restrict_to_ghost).
  BakeOptions on_proxy = options;
  on_proxy.material.paint = restrict_to_ghost(proxy.map, static_cast<int>(proxy.V.rows()),
                                              part.mass, part.paint(options.material.paint));
  on_proxy.region = part.proxy_region(proxy);
  Basis basis = rest_state(proxy.V, proxy.F, on_proxy, fine.scale);
  basis.timings = timed.timings;
  // A proxy vertex's index means nothing to the artist: errors name the nearest of its fine
  // vertices.
  const VertexName fine_vertex = [&](int p) {
    return message(vertex_at(V, part.mesh_vertex(nearest_fine_vertex(proxy, part.V, p))),
                   ", the nearest of the mesh's vertices to the proxy's vertex ", p);
  };
  {
    const MovingPart proxy_part(proxy.V, proxy.F, basis.mass, on_proxy.region);
    basis = bake_stages(proxy.V, proxy_part, on_proxy, std::move(basis), fine_vertex, progress);
  }
  BakeRun{options, basis, progress}.stage(stages::kProlongation, [&] {
    basis.prolongation = part.on_mesh(prolongation_to_proxy(part.V, proxy.V, proxy.F, proxy.map));
    const Eigen::VectorXi ghost_map = basis.ghost_map(proxy.map);
    basis.ghost_map = part.on_mesh(ghost_map);
    basis.rest = std::move(fine.rest);
    basis.mass = std::move(fine.mass);
    basis.material.paint.weights = std::move(fine.material.paint.weights);
    basis.region = std::move(fine.region);
  });
  return basis;
}

}  // namespace modal_deform
