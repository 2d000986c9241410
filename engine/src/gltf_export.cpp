// Animated glTF 2.0 (.glb) export through tinygltf (hsi/gltf_export.h).
#include "hsi/gltf_export.h"

#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "hsi/basis.h"
#include "hsi/harmonic_map.h"
#include "hsi/png_import.h"
#include "hsi/triangulate.h"

#include <tiny_gltf.h>  // declarations only: the implementation is Debian's libtinygltf.so

namespace hsi {
namespace {

constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

struct Builder {
  tinygltf::Model model;
  std::vector<unsigned char>& data() { return model.buffers[0].data; }

  int view(const void* bytes, size_t size, int target) {
    while (data().size() % 4) data().push_back(0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = data().size();
    v.byteLength = size;
    v.target = target;
    const auto* p = static_cast<const unsigned char*>(bytes);
    data().insert(data().end(), p, p + size);
    model.bufferViews.push_back(v);
    return static_cast<int>(model.bufferViews.size()) - 1;
  }

  // A float accessor of `components` per element, with exact min/max when asked.
  int floats(const std::vector<float>& v, int components, int type, int target, bool min_max, const std::string& name = "") {
    tinygltf::Accessor a;
    a.bufferView = view(v.data(), v.size() * sizeof(float), target);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = v.size() / static_cast<size_t>(components);
    a.type = type;
    a.name = name;
    if (min_max) {
      a.minValues.assign(static_cast<size_t>(components), std::numeric_limits<double>::infinity());
      a.maxValues.assign(static_cast<size_t>(components), -std::numeric_limits<double>::infinity());
      for (size_t i = 0; i < v.size(); ++i) {
        const size_t c = i % static_cast<size_t>(components);
        a.minValues[c] = std::min(a.minValues[c], static_cast<double>(v[i]));
        a.maxValues[c] = std::max(a.maxValues[c], static_cast<double>(v[i]));
      }
    }
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size()) - 1;
  }
};

std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string() + ": cannot open the scene's texture");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

std::string encode_glb(const Scene& scene, const FrameFile& frames, const GltfOptions& o, GltfStats* stats) {
  const int F = static_cast<int>(frames.frames.size());
  if (F < 1) throw InputError("glTF export: there are no frames");
  if (o.max_frames < 2) throw InputError("glTF export: at least 2 frames must be sampled (max_frames = " + std::to_string(o.max_frames) + ")");
  if (!(o.seconds_per_time_unit > 0)) throw InputError("glTF export: seconds per time unit must be positive");
  const int K = std::min(F, o.max_frames);
  std::vector<int> picks;
  for (int k = 0; k < K; ++k) picks.push_back(K == 1 ? 0 : static_cast<int>(std::lround(static_cast<double>(k) * (F - 1) / (K - 1))));
  for (int i : picks) {
    const StoredFrame& f = frames.frames[static_cast<size_t>(i)];
    if (f.map.phi.size() != basis_size(frames.cage))
      throw InputError("glTF export: frame " + std::to_string(i) + " does not fit the cage");
    if (!f.certified && !o.allow_uncertified)
      throw InputError("glTF export: frame " + std::to_string(i) + " (t = " + std::to_string(f.t) +
                       ") is not certified locally injective; it is not exported as if it were good");
  }
  std::vector<std::optional<NewtonStop>> stop_of;  // per sampled frame
  for (int i : picks) {
    try {
      stop_of.push_back(stored_stop(frames.frames[static_cast<size_t>(i)], static_cast<size_t>(i)));
    } catch (const InputError& e) {
      throw InputError(std::string("glTF export: ") + e.what());
    }
  }

  TriangulateOptions to;
  to.max_edge = edge_for_vertex_count(scene.shape, std::max(16, o.mesh_vertices));
  const TriMesh mesh = triangulate(scene.shape, to);
  const size_t P = mesh.vertices.size();
  const BasisRows rows = evaluate_basis(frames.cage, mesh.vertices, kBasisC);
  std::vector<std::vector<float>> pos;  // per sampled frame, x y 0 per vertex
  for (int i : picks) {
    const VectorXcd f = evaluate_map(rows, frames.frames[static_cast<size_t>(i)].map).f;
    std::vector<float> p(3 * P);
    for (size_t v = 0; v < P; ++v) {
      p[3 * v] = static_cast<float>(f(static_cast<Eigen::Index>(v)).real());
      p[3 * v + 1] = static_cast<float>(f(static_cast<Eigen::Index>(v)).imag());
      p[3 * v + 2] = 0.0f;
    }
    pos.push_back(std::move(p));
  }

  Builder b;
  b.model.buffers.emplace_back();
  b.model.asset.version = "2.0";
  b.model.asset.generator = "hsi 0.1.0 (harmonic shape interpolation)";

  // Texture coordinates: the rest position in the texture's rectangle (v down).
  const std::array<double, 4> rect = scene.texture_rect_or_bounds();
  std::vector<float> uv(2 * P);
  for (size_t v = 0; v < P; ++v) {
    uv[2 * v] = static_cast<float>((mesh.vertices[v].real() - rect[0]) / (rect[2] - rect[0]));
    uv[2 * v + 1] = static_cast<float>((rect[3] - mesh.vertices[v].imag()) / (rect[3] - rect[1]));
  }
  std::vector<uint32_t> indices;
  for (const auto& t : mesh.triangles)
    for (int k : t) indices.push_back(static_cast<uint32_t>(k));

  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.attributes["POSITION"] = b.floats(pos[0], 3, TINYGLTF_TYPE_VEC3, kArrayBuffer, true, "frame 0");
  if (!scene.texture.empty()) prim.attributes["TEXCOORD_0"] = b.floats(uv, 2, TINYGLTF_TYPE_VEC2, kArrayBuffer, false, "uv");
  {
    tinygltf::Accessor a;
    a.bufferView = b.view(indices.data(), indices.size() * 4, kElementArrayBuffer);
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    a.count = indices.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    b.model.accessors.push_back(a);
    prim.indices = static_cast<int>(b.model.accessors.size()) - 1;
  }
  tinygltf::Value::Array names;
  for (size_t k = 1; k < pos.size(); ++k) {
    std::vector<float> d(3 * P);
    for (size_t i = 0; i < d.size(); ++i) d[i] = pos[k][i] - pos[0][i];
    char name[64];
    std::snprintf(name, sizeof name, "frame %d", picks[k]);
    prim.targets.push_back({{"POSITION", b.floats(d, 3, TINYGLTF_TYPE_VEC3, kArrayBuffer, true, name)}});
    names.emplace_back(std::string(name));
  }

  // Material: the scene's texture (PNG bytes as they are), unlit where supported.
  tinygltf::Material mat;
  mat.name = scene.name.empty() ? "shape" : scene.name;
  mat.doubleSided = true;
  mat.pbrMetallicRoughness.metallicFactor = 0;
  mat.pbrMetallicRoughness.roughnessFactor = 1;
  mat.extensions["KHR_materials_unlit"] = tinygltf::Value(tinygltf::Value::Object());
  b.model.extensionsUsed.push_back("KHR_materials_unlit");
  bool textured = false;
  if (!scene.texture.empty()) {
    const std::string png = read_bytes(scene.texture_path());
    // Decoded once here, so that a corrupt or truncated texture is refused rather
    // than embedded in a file that viewers then fail to load.
    check_png_texture(std::span(reinterpret_cast<const unsigned char*>(png.data()), png.size()),
                      scene.texture_path().string());
    tinygltf::Image img;
    img.name = scene.texture.filename().string();
    img.mimeType = "image/png";
    img.bufferView = b.view(png.data(), png.size(), 0);
    b.model.bufferViews.back().target = 0;
    b.model.images.push_back(img);
    tinygltf::Sampler s;
    const bool nearest = scene.texture_filter == TextureFilter::Nearest;  // as the renderers sample it
    s.magFilter = nearest ? TINYGLTF_TEXTURE_FILTER_NEAREST : TINYGLTF_TEXTURE_FILTER_LINEAR;
    s.minFilter = nearest ? TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST : TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
    s.wrapS = s.wrapT = TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE;
    b.model.samplers.push_back(s);
    tinygltf::Texture tex;
    tex.source = 0;
    tex.sampler = 0;
    b.model.textures.push_back(tex);
    mat.pbrMetallicRoughness.baseColorTexture.index = 0;
    textured = true;
  } else {
    mat.pbrMetallicRoughness.baseColorFactor = {0.78, 0.84, 0.92, 1.0};
  }
  b.model.materials.push_back(mat);
  prim.material = 0;

  tinygltf::Mesh m;
  m.name = mat.name;
  m.primitives.push_back(prim);
  m.weights.assign(pos.size() - 1, 0.0);
  m.extras = tinygltf::Value(tinygltf::Value::Object{{"targetNames", tinygltf::Value(names)}});
  b.model.meshes.push_back(m);
  tinygltf::Node node;
  node.mesh = 0;
  node.name = mat.name;
  b.model.nodes.push_back(node);
  tinygltf::Scene sc;
  sc.nodes.push_back(0);
  b.model.scenes.push_back(sc);
  b.model.defaultScene = 0;

  // The animation: key k shows sampled frame k alone (target k − 1 at weight 1).
  if (pos.size() > 1) {
    const double t0 = frames.frames[static_cast<size_t>(picks[0])].t;
    std::vector<float> times, weights;
    for (size_t k = 0; k < pos.size(); ++k) {
      times.push_back(static_cast<float>((frames.frames[static_cast<size_t>(picks[k])].t - t0) * o.seconds_per_time_unit));
      if (k > 0 && !(times[k] > times[k - 1]))
        throw InputError("glTF export: sampled frames " + std::to_string(picks[k - 1]) + " and " + std::to_string(picks[k]) +
                         " have the same animation time");
      for (size_t j = 0; j + 1 < pos.size(); ++j) weights.push_back(j + 1 == k ? 1.0f : 0.0f);
    }
    tinygltf::AnimationSampler s;
    s.input = b.floats(times, 1, TINYGLTF_TYPE_SCALAR, 0, true, "time");
    s.output = b.floats(weights, 1, TINYGLTF_TYPE_SCALAR, 0, false, "weights");
    b.model.bufferViews[static_cast<size_t>(b.model.accessors[static_cast<size_t>(s.input)].bufferView)].target = 0;
    s.interpolation = o.step ? "STEP" : "LINEAR";
    tinygltf::AnimationChannel c;
    c.sampler = 0;
    c.target_node = 0;
    c.target_path = "weights";
    tinygltf::Animation an;
    an.name = "interpolation";
    // Each key's frame and its flags, so that a consumer can tell a frame whose Newton
    // solve stopped early (converged false) from a converged one, and why it stopped
    // ("stop": the reason's name, as report.json's; "not recorded" where the frames do not say).
    tinygltf::Value::Array keys;
    for (size_t k = 0; k < pos.size(); ++k) {
      const StoredFrame& f = frames.frames[static_cast<size_t>(picks[k])];
      keys.emplace_back(tinygltf::Value::Object{{"frame", tinygltf::Value(picks[k])},
                                                {"t", tinygltf::Value(f.t)},
                                                {"certified", tinygltf::Value(f.certified)},
                                                {"keyframe", tinygltf::Value(f.keyframe)},
                                                {"converged", tinygltf::Value(f.converged)},
                                                {"stop", tinygltf::Value(std::string(stop_name(stop_of[k])))}});
    }
    an.extras = tinygltf::Value(tinygltf::Value::Object{{"frames", tinygltf::Value(keys)}});
    an.samplers.push_back(s);
    an.channels.push_back(c);
    b.model.animations.push_back(an);
  }

  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&b.model, out, false, true)) throw InputError("glTF export: tinygltf could not write the model");
  std::string bytes = out.str();
  if (stats) *stats = {static_cast<int>(P), mesh.triangle_count(), static_cast<int>(pos.size()) - 1, textured, bytes.size()};
  return bytes;
}

void write_glb(const std::filesystem::path& path, const Scene& scene, const FrameFile& frames, const GltfOptions& options, GltfStats* stats) {
  write_file_atomic(path, encode_glb(scene, frames, options, stats));
}

}  // namespace hsi
