// hsi info SCENE: what hsi sees in a scene (loops, cage, map space, samples).
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "hsi/map_space.h"
#include "hsi/scene_io.h"
#include "hsi/draw/plot.h"

namespace hsi::cli {

using draw::plot_cage;

void register_info(CLI::App& app) {
  struct Opts {
    std::string scene, png, json;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("info", "Print a scene's loops, cage, map-space size and samples; validate it");
  cmd->add_option("scene", o->scene, "Scene file (.json)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--png", o->png, "Also draw the shape, cage, hole points and samples to this PNG");
  cmd->add_option("--json", o->json, "Also write the report as JSON to this file");
  cmd->callback([o] {
    const Scene scene = load_scene(o->scene);
    const Cage cage = scene_cage(scene);
    const BoundarySamples G = sample_boundary(scene.shape, scene.samples);
    const std::vector<int> H = hessian_subset(G, scene.hessian_ratio);
    const MapSpace map_space(cage, Gauge::Map), metric_space(cage, Gauge::ModuloRigid);
    // Conditioning of the reduced basis on 2000 boundary points (more rows than unknowns).
    const BoundarySamples dense = sample_boundary(scene.shape, std::max(2000, map_space.dim()));
    const BasisRows rows = evaluate_basis(cage, dense.points, kBasisC | kBasisD);
    const Conditioning cf = conditioning(map_space, rows);
    const Conditioning cm = conditioning(metric_space, rows);

    nlohmann::json r;
    r["scene"] = o->scene;
    r["name"] = scene.name;
    r["valid"] = true;
    r["area"] = area(scene.shape);
    r["loops"] = nlohmann::json::array();
    std::printf("scene      %s%s%s\n", o->scene.c_str(), scene.name.empty() ? "" : "  (", scene.name.empty() ? "" : (scene.name + ")").c_str());
    std::printf("validation ok: %d loop%s, area %.6g\n", scene.shape.loop_count(), scene.shape.loop_count() == 1 ? "" : "s",
                area(scene.shape));
    for (int k = 0; k < scene.shape.loop_count(); ++k) {
      const int nv = static_cast<int>(scene.shape.loop(k).size());
      const int nc = static_cast<int>(cage.loops[static_cast<size_t>(k)].size());
      std::printf("  %-10s %5d vertices, cage %3d vertices", loop_name(k).c_str(), nv, nc);
      nlohmann::json lj{{"loop", loop_name(k)}, {"vertices", nv}, {"cage_vertices", nc}};
      if (k > 0) {
        const cd rho = cage.hole_points[static_cast<size_t>(k - 1)];
        std::printf(", hole point (%.4g, %.4g)", rho.real(), rho.imag());
        lj["hole_point"] = {rho.real(), rho.imag()};
      }
      std::printf("\n");
      r["loops"].push_back(lj);
    }
    std::printf("cage       %s, %d vertices, clearance %.4g (%.2f%% of the size)\n", scene.cage ? "user-given" : "automatic",
                cage.vertex_count(), cage_clearance(scene.shape, cage),
                100 * cage_clearance(scene.shape, cage) / bounding_box(scene.shape).diagonal());
    std::printf("map space  n = %d complex columns (m_outer + sum(m_hole - 2) + N), basis size m + N = %d\n", map_space.n(),
                map_space.full_size());
    std::printf("           reduced real dims: %d (map gauge), %d (metric gauge)\n", map_space.dim(), metric_space.dim());
    std::printf("           singular values on %zu boundary points: f: [%.3g, %.3g], (f_z, conj f_zbar): [%.3g, %.3g]\n",
                dense.size(), cf.sigma_min, cf.sigma_max, cm.sigma_min, cm.sigma_max);
    std::printf("samples    |G| = %zu, |H| = %zu (r = %.0f%%)\n", G.size(), H.size(), 100 * scene.hessian_ratio);
    std::printf("texture    %s\n", scene.texture.empty() ? "(none)" : scene.texture_path().string().c_str());
    r["cage"] = {{"vertices", cage.vertex_count()}, {"user_given", scene.cage.has_value()},
                 {"clearance", cage_clearance(scene.shape, cage)}};
    r["map_space"] = {{"n", map_space.n()},
                      {"basis_size", map_space.full_size()},
                      {"dim_map_gauge", map_space.dim()},
                      {"dim_metric_gauge", metric_space.dim()},
                      {"sigma_min_f", cf.sigma_min},
                      {"sigma_max_f", cf.sigma_max},
                      {"sigma_min_metric", cm.sigma_min},
                      {"sigma_max_metric", cm.sigma_max}};
    r["samples"] = {{"G", G.size()}, {"H", H.size()}};
    if (!o->json.empty()) {
      std::ofstream out(o->json);
      out << r.dump(2) << "\n";
      if (!out) throw std::runtime_error("cannot write " + o->json);
    }
    if (!o->png.empty()) {
      plot_cage(o->png, scene.shape, cage, &G);
      std::printf("drawing    %s\n", o->png.c_str());
    }
  });
}

}  // namespace hsi::cli
