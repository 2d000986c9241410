// hsi info SCENE: what hsi sees in a scene (loops, cage, map space, samples, keyframes)
// and whether it can be interpolated, and if not, why.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "hsi/interpolation.h"
#include "hsi/keyframes.h"
#include "hsi/map_space.h"
#include "hsi/scene_io.h"
#include "hsi/draw/plot.h"
#include "hsi/scene_texture.h"
#include "hsi/shape_setup.h"

namespace hsi::cli {

using draw::plot_cage;

void register_info(CLI::App& app) {
  struct Opts {
    std::string scene, png, json;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Print a scene's loops, cage, map-space size, samples and keyframes (time, how given, certified,\n"
      "certified distortion bounds); validate it and say whether it can be interpolated, and if not, why.\n"
      "Keyframes given only by targets are not solved here (hsi keyframes does that).");
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
    std::printf("shape ok   %d loop%s, area %.6g\n", scene.shape.loop_count(), scene.shape.loop_count() == 1 ? "" : "s",
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
    if (scene.texture.empty())
      std::printf("texture    (none)\n");
    else
      std::printf("texture    %s (%s filtering)\n", scene.texture_path().string().c_str(), texture_filter_name(scene.texture_filter));
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
    if (!scene.texture.empty()) r["texture_filter"] = texture_filter_name(scene.texture_filter);

    // Keyframes: how each is given and, for those with coefficients, their certificate.
    // The verdict says plainly whether hsi interpolate can run, and why not.
    std::vector<std::string> blockers;
    if (scene.keyframes.size() < 2)
      blockers.push_back("it has " + std::to_string(scene.keyframes.size()) + " keyframe" + (scene.keyframes.size() == 1 ? "" : "s") +
                         "; interpolation needs at least two (" + kHowToAddKeyframes + ")");
    std::unique_ptr<ShapeSetup> setup;
    if (std::any_of(scene.keyframes.begin(), scene.keyframes.end(), [](const Keyframe& k) { return k.coefficients.has_value(); }))
      setup = std::make_unique<ShapeSetup>(scene.shape, cage, scene.samples, scene.hessian_ratio);
    r["keyframes"] = nlohmann::json::array();
    std::printf("keyframes  %zu%s\n", scene.keyframes.size(), scene.keyframes.empty() ? " (none)" : "");
    bool unsolved = false;
    for (size_t k = 0; k < scene.keyframes.size(); ++k) {
      const Keyframe& key = scene.keyframes[k];
      const std::string given = key.coefficients ? (key.targets.empty() ? "coefficients" : "coefficients (solved from targets)")
                                                 : "targets only (not solved yet)";
      nlohmann::json kj{{"index", k}, {"time", key.time}, {"given", key.coefficients ? "coefficients" : "targets"},
                        {"targets", key.targets.size()}};
      std::printf("  %-3zu t = %-8.4g %-34s ", k, key.time, given.c_str());
      if (!key.coefficients) {
        unsolved = true;
        kj["certified"] = nullptr;
        std::printf("certified: not yet (hsi keyframes solves it)\n");
      } else {
        std::string why;
        CertificateResult c;
        try {
          (void)import_keyframe(*setup, *key.coefficients, "keyframe " + std::to_string(k));
          c = setup->certifier.certify(*key.coefficients);
        } catch (const InputError& e) {
          why = e.what();
        }
        kj["certified"] = why.empty();
        if (why.empty()) {
          const Distortion d = certified_distortion(c);
          std::printf("certified; certified bounds: sigma1 <= %.4g, sigma2 >= %.4g, sigma1/sigma2 <= %.4g\n", d.sigma1_max, d.sigma2_min,
                      d.conformal_max);
          kj["certified_bounds"] = {{"sigma1_max", d.sigma1_max}, {"sigma2_min", d.sigma2_min}, {"conformal_max", d.conformal_max},
                                    {"isometric_max", d.isometric_max}};
        } else {
          std::printf("NOT CERTIFIED: %s\n", why.c_str());
          kj["why"] = why;
          blockers.push_back(why);
        }
      }
      r["keyframes"].push_back(kj);
    }
    r["interpolable"] = blockers.empty();
    if (!blockers.empty()) {
      std::printf("interpolation: NOT POSSIBLE: %s\n", blockers.front().c_str());
      for (size_t b = 1; b < blockers.size(); ++b) std::printf("               also: %s\n", blockers[b].c_str());
      r["not_interpolable_because"] = blockers;
    } else if (unsolved) {
      std::printf("interpolation: possible once the keyframes given by targets are solved (hsi interpolate and hsi keyframes "
                  "solve them; targets that cannot be reached without folding give the closest certified map)\n");
    } else {
      std::printf("interpolation: ready (every keyframe certified)\n");
    }
    if (!o->json.empty()) {
      write_file_atomic(o->json, r.dump(2) + "\n");
    }
    if (!o->png.empty()) {
      draw::CagePlot extras;
      extras.handles = scene.handles;
      std::optional<SceneTexture> tex;
      if (!scene.texture.empty()) tex = scene_texture(scene, o->scene);
      extras.texture = tex ? &*tex : nullptr;
      plot_cage(o->png, scene.shape, cage, &G, 800, extras);
      std::printf("drawing    %s (%s)\n", o->png.c_str(),
                  tex ? (std::string("over the texture, ") + texture_filter_name(tex->filter) + " filtering").c_str()
                      : "no texture");
    }
  });
}

}  // namespace hsi::cli
