// The bad-input corpus (issue #10): malformed inputs a user will produce, each refused
// with an hsi::InputError whose message names the file, the problem and where, never
// a crash or a silently wrong result. Scene files are checked in (tests/corpus/scenes/,
// one kind per file, every file listed below); PNGs, frames and baked files are made
// here from valid ones and then broken.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <span>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>
#include <zlib.h>

#include "hsi/baked.h"
#include "hsi/baked_runtime.h"
#include "hsi/frames_io.h"
#include "hsi/gltf_export.h"
#include "hsi/keyframes.h"
#include "hsi/png_import.h"
#include "hsi/scene_io.h"
#include "hsi/scene_sequence.h"
#include "hsi/shape_setup.h"
#if __has_include("hsi/png.h")  // the one PNG reader, the engine's
#include "hsi/png.h"
#define HSI_TEST_VK_IMAGE 1
#endif

using namespace hsi;
namespace fs = std::filesystem;

namespace {

const fs::path kCorpus = fs::path(HSI_TESTS_DIR) / "corpus" / "scenes";

fs::path tmp_dir(const std::string& name) {
  const fs::path d = fs::path(HSI_TEST_TMP) / "bad_input" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  REQUIRE(f.good());
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs f, which must throw InputError; returns its message (empty if it did not throw).
template <class F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    FAIL("threw something other than InputError: " << e.what());
  }
  return {};
}

void check_message(const std::string& msg, const std::vector<std::string>& parts) {
  INFO("message: " << msg);
  REQUIRE_FALSE(msg.empty());  // it did throw
  for (const std::string& p : parts) {
    INFO("expected to contain: " << p);
    CHECK(msg.find(p) != std::string::npos);
  }
}

struct Case {
  const char* file;
  std::vector<std::string> expect;  // substrings of the message (besides the file's path)
};

// Refused while loading (load_scene): syntax, types, structure, geometry, settings.
const std::vector<Case> kLoadCases = {
    // JSON syntax
    {"empty.json", {"invalid JSON at line 1", "unexpected end of input"}},
    {"whitespace_only.json", {"invalid JSON at line 3", "unexpected end of input"}},
    {"truncated.json", {"invalid JSON at line 2", "unexpected end of input"}},
    {"trailing_comma.json", {"invalid JSON at line 1", "unexpected ']'"}},
    {"single_quotes.json", {"invalid JSON at line 1", "invalid literal"}},
    {"nan_literal.json", {"invalid JSON at line 1", "invalid literal"}},
    {"infinity_literal.json", {"invalid JSON at line 1", "invalid literal"}},
    {"number_overflow.json", {"invalid JSON at line 1, column 45", "number overflow", "1e400"}},
    {"bad_utf8.json", {"invalid JSON at line 1, column 27: syntax error while parsing value - invalid string: ill-formed UTF-8 byte; last read: '\"\\xFF'"}},
    {"two_documents.json", {"invalid JSON at line 1", "expected end of input"}},
    {"deep_nesting.json", {"shape.outer[0]: expected a point [x, y], got an array of 1"}},
    // structure, types, versions
    {"top_level_array.json", {"expected a JSON object at the top level, got array"}},
    {"missing_version.json", {"missing \"hsi_scene\""}},
    {"unknown_version.json", {"hsi_scene: unsupported version 99", "reads versions 1 to 2"}},
    {"version_wraps.json", {"hsi_scene: unsupported version 4294967297"}},
    {"version_string.json", {"hsi_scene: expected an integer version, got string"}},
    {"version_fraction.json", {"hsi_scene: expected an integer version, got number"}},
    {"version_huge.json", {"hsi_scene: expected an integer version, got number"}},
    {"name_not_string.json", {"name: expected a string"}},
    {"missing_shape.json", {"missing \"shape\""}},
    {"shape_not_object.json", {"shape: expected an object"}},
    {"missing_outer.json", {"shape: missing \"outer\""}},
    {"outer_not_array.json", {"shape.outer: expected an array of points", "got string"}},
    {"point_three_numbers.json", {"shape.outer[1]: expected a point [x, y], got an array of 3"}},
    {"point_is_object.json", {"shape.outer[1]: expected a point [x, y], got object"}},
    {"coordinate_string.json", {"shape.outer[1][1]: expected a number, got string"}},
    {"coordinate_null.json", {"shape.outer[2][0]: expected a number, got null"}},
    {"coordinate_bool.json", {"shape.outer[2][1]: expected a number, got boolean"}},
    {"holes_not_array.json", {"shape.holes: expected an array of loops"}},
    // geometry
    {"huge_coordinate.json", {"shape: outer loop vertex 1 has a coordinate beyond 1e12", "rescale"}},
    {"hole_nan.json", {"invalid JSON at line 1, column 90", "number overflow", "1e999"}},
    {"two_vertices.json", {"shape: outer loop has 2 vertices; a loop needs at least 3"}},
    {"empty_outer.json", {"shape: outer loop has 0 vertices"}},
    {"collinear.json", {"shape: outer loop intersects itself"}},
    {"sliver.json", {"shape: outer loop encloses (almost) no area"}},
    {"duplicate_consecutive.json", {"shape: outer loop has a zero-length outer loop edge 1", "vertices 1 and 2 coincide at (4, 0)"}},
    {"duplicate_closing_point.json", {"zero-length outer loop edge 4", "vertices 4 and 0 coincide", "do not repeat its first vertex"}},
    {"pinched_loop.json", {"shape: outer loop intersects itself"}},
    {"bow_tie.json", {"shape: outer loop intersects itself: outer loop edge 0", "meets outer loop edge 2"}},
    {"hole_bow_tie.json", {"shape: hole 1 intersects itself"}},
    {"hole_two_vertices.json", {"shape: hole 1 has 2 vertices"}},
    {"hole_outside.json", {"shape: hole 1 lies outside the outer loop", "(5, 5)"}},
    {"hole_crosses_outer.json", {"shape: hole 1 crosses the outer loop"}},
    {"hole_touches_outer.json", {"shape: hole 1 crosses the outer loop"}},
    {"hole_equals_outer.json", {"shape: hole 1 crosses the outer loop"}},
    {"holes_overlap.json", {"shape: hole 2 crosses the hole 1"}},
    {"hole_inside_hole.json", {"shape: hole 2 lies inside hole 1", "holes must be disjoint"}},
    // texture
    {"texture_not_string.json", {"texture: expected a file path string"}},
    {"texture_rect_short.json", {"texture_rect: expected [x0, y0, x1, y1]"}},
    {"texture_rect_inverted.json", {"texture_rect: needs x1 > x0 and y1 > y0"}},
    // cage
    {"cage_not_object.json", {"cage: expected an object"}},
    {"cage_loops_only.json", {"cage: a user cage needs both \"loops\" and \"hole_points\""}},
    {"cage_cuts_shape.json", {"cage: cage loop of the outer loop touches the shape", "outer loop edge"}},
    {"cage_inside_shape.json", {"cage: the cage's outer loop does not enclose the shape"}},
    {"cage_too_close.json", {"cage: the cage loop of the outer loop comes within", "of the shape's outer loop", "a user cage that fits"}},
    {"cage_wrong_loop_count.json", {"cage: the cage has 1 loops; the shape has 2"}},
    {"cage_hole_point_outside_hole.json", {"cage: hole point 1 lies outside hole 1"}},
    {"cage_loop_two_vertices.json", {"cage.loops[0]: needs at least 3 vertices"}},
    {"cage_self_intersecting.json", {"cage: cage loop of the outer loop"}},
    {"cage_max_vertices_small.json", {"cage.max_vertices_per_loop: expected an integer between 4 and 100,000"}},
    {"cage_clearance_negative.json", {"cage.clearance: must lie in (0, 1]"}},
    {"cage_clearance_huge.json", {"cage.clearance: must lie in (0, 1]"}},
    // settings
    {"samples_too_few.json", {"samples: expected an integer between 100 and 10,000,000"}},
    {"samples_fraction.json", {"samples: expected an integer between 100 and 10,000,000"}},
    {"samples_huge.json", {"samples: expected an integer between 100 and 10,000,000"}},
    {"hessian_ratio_zero.json", {"hessian_ratio: must lie in (0, 1]"}},
    {"hessian_ratio_string.json", {"hessian_ratio: expected a number, got string"}},
    // handles and keyframes
    {"handle_outside.json", {"handles[1]: lies outside the shape"}},
    {"handle_in_hole.json", {"handles[0]: lies outside the shape, in hole 1"}},
    {"handles_not_array.json", {"handles: expected an array of points"}},
    {"keyframes_not_array.json", {"keyframes: expected an array"}},
    {"keyframe_not_object.json", {"keyframes[0]: expected an object"}},
    {"keyframe_missing_time.json", {"keyframes[0]: missing \"time\""}},
    {"keyframe_time_string.json", {"keyframes[0].time: expected a number, got string"}},
    {"keyframe_times_decrease.json", {"keyframes[1].time: keyframe times must increase"}},
    {"keyframe_times_equal.json", {"keyframes[1].time: keyframe times must increase"}},
    {"keyframe_targets_count.json", {"keyframes[0].targets: has 1 targets; the scene has 2 handles"}},
    {"keyframe_target_nan.json", {"invalid JSON at line 1, column 126", "number overflow"}},
    {"keyframe_empty.json", {"keyframes[0]: needs \"targets\" (one per handle) or coefficients"}},
    {"keyframe_phi_without_psi.json", {"keyframes[0]: coefficients need both \"phi\" and \"psi\""}},
    {"keyframe_coefficients_without_cage.json", {"keyframes[0]: coefficients need the scene's cage"}},
    {"keyframe_phi_wrong_length.json", {"keyframes[0].phi: has 3 coefficients; the cage needs 4"}},
    {"keyframe_phi_psi_lengths_differ.json", {"keyframes[0]: \"phi\" and \"psi\" differ in length"}},
    {"keyframe_layout_unknown.json", {"keyframes[0].layout: expected \"full\" or \"reduced\", got \"compact\""}},
    // misspelt keys: refused with their JSON path and the nearest known key, never ignored
    {"misspelt_key.json", {"sample: unknown key; the nearest known key is \"samples\""}},
    {"shape_misspelt_key.json", {"shape.hole: unknown key; the nearest known key is \"holes\""}},
    {"keyframe_misspelt_key.json", {"keyframes[1].tme: unknown key; the nearest known key is \"time\""}},
};

// Load, but are refused when their keyframes are made certified (or interpolated).
const std::vector<Case> kKeyframeCases = {
    {"keyframe_folds.json", {"keyframe 1 is not locally injective"}},
    {"keyframe_reflects.json", {"keyframe 1 is not locally injective"}},
    {"keyframe_collapses.json", {"keyframe 0 is not locally injective"}},
    {"keyframe_log_terms_mismatch.json", {"keyframe 1: hole 1 column: psi must equal conj(phi)"}},
    {"one_keyframe.json", {"interpolation needs at least two keyframes (it has 1)", "hsi-viewer SCENE", "hsi keyframes SCENE --handle X,Y"}},
};

// A scene made into certified keyframes and interpolated, as hsi interpolate does.
void make_frames(const fs::path& scene_path) {
  Scene s = load_scene(scene_path);
  SceneSequenceOptions o;
  o.frames = 3;
  o.samples = 400;
  (void)interpolate_scene(s, o);
}

}  // namespace

TEST_CASE("bad-input corpus: every malformed scene is refused with a message naming file, problem and place", "[bad_input]") {
  for (const Case& c : kLoadCases) {
    DYNAMIC_SECTION(c.file) {
      const fs::path p = kCorpus / c.file;
      REQUIRE(fs::exists(p));
      std::vector<std::string> parts = c.expect;
      parts.push_back(p.string());
      check_message(input_error([&] { (void)load_scene(p); }), parts);
    }
  }
  for (const Case& c : kKeyframeCases) {
    DYNAMIC_SECTION(c.file) {
      const fs::path p = kCorpus / c.file;
      REQUIRE_NOTHROW(load_scene(p));  // well-formed: refused only when the keyframes are certified
      std::vector<std::string> parts = c.expect;
      parts.push_back(p.string() + ": ");  // the file is named even though it loaded
      check_message(input_error([&] { make_frames(p); }), parts);
    }
  }
}

TEST_CASE("bad-input corpus: every file in tests/corpus/scenes has its expected message here", "[bad_input]") {
  std::set<std::string> listed;
  for (const Case& c : kLoadCases) CHECK(listed.insert(c.file).second);
  for (const Case& c : kKeyframeCases) CHECK(listed.insert(c.file).second);
  std::set<std::string> on_disk;
  for (const auto& e : fs::directory_iterator(kCorpus)) on_disk.insert(e.path().filename().string());
  CHECK(on_disk == listed);
  CHECK(listed.size() >= 40);
}

TEST_CASE("bad-input corpus: scenes refused from memory name the source given", "[bad_input]") {
  // The same parser behind the C API and the engine: the source name is in every message.
  const std::string text = read_bytes(kCorpus / "bow_tie.json");
  check_message(input_error([&] { (void)parse_scene(text, ".", "my-scene"); }), {"my-scene: shape: outer loop intersects itself"});
  check_message(input_error([&] { (void)load_scene(kCorpus / "no_such_file.json"); }), {"no_such_file.json: cannot open the scene file"});
  check_message(input_error([&] { (void)load_scene(kCorpus); }), {"scenes"});  // a directory
}

// ---- PNG: sprites (import_png_alpha) and textures ------------------------------------

namespace {

void put32(std::string& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<char>((v >> s) & 0xff));
}

std::string chunk(const char* type, const std::string& data) {
  std::string c;
  put32(c, static_cast<uint32_t>(data.size()));
  std::string body = std::string(type, 4) + data;
  c += body;
  put32(c, static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
  return c;
}

std::string ihdr(uint32_t w, uint32_t h, int depth, int color) {
  std::string d;
  put32(d, w);
  put32(d, h);
  d += {static_cast<char>(depth), static_cast<char>(color), 0, 0, 0};
  return chunk("IHDR", d);
}

const std::string kSig = "\x89PNG\r\n\x1a\n";

// An 8-bit RGBA (colour type 6) or RGB (2) image, alpha from the callback.
template <class Alpha>
std::string png(int w, int h, int color, Alpha alpha) {
  std::string raw;
  for (int y = 0; y < h; ++y) {
    raw.push_back(0);
    for (int x = 0; x < w; ++x) {
      raw += {char(40), char(90), char(200)};
      if (color == 6) raw.push_back(static_cast<char>(alpha(x, y)));
    }
  }
  uLongf n = compressBound(static_cast<uLong>(raw.size()));
  std::string z(n, '\0');
  REQUIRE(compress(reinterpret_cast<Bytef*>(z.data()), &n, reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size())) == Z_OK);
  z.resize(n);
  return kSig + ihdr(static_cast<uint32_t>(w), static_cast<uint32_t>(h), 8, color) + chunk("IDAT", z) + chunk("IEND", "");
}

int disc(int x, int y) { return (x - 16) * (x - 16) + (y - 16) * (y - 16) < 100 ? 255 : 0; }

struct PngCase {
  std::string name;
  std::string bytes;
  std::vector<std::string> expect;
};

std::vector<PngCase> png_cases() {
  const std::string good = png(32, 32, 6, disc);
  std::string bad_crc = good;
  bad_crc[bad_crc.size() - 20] ^= 0x40;  // inside the IDAT data: its CRC fails
  std::string bad_zlib = good;
  bad_zlib[8 + 25 + 8 + 2] ^= 0x7f;  // the deflate stream just past the zlib header (CRC recomputed below)
  {
    // Recompute the IDAT CRC so that only the deflate data is broken.
    const size_t at = 8 + 25;
    const uint32_t len = (uint32_t(uint8_t(bad_zlib[at])) << 24) | (uint32_t(uint8_t(bad_zlib[at + 1])) << 16) |
                         (uint32_t(uint8_t(bad_zlib[at + 2])) << 8) | uint32_t(uint8_t(bad_zlib[at + 3]));
    const std::string body = bad_zlib.substr(at + 4, 4 + len);
    std::string c;
    put32(c, static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
    bad_zlib.replace(at + 8 + len, 4, c);
  }
  return {
      {"empty.png", "", {"not a PNG file", "the file is empty"}},
      {"text.png", "this is not an image\n", {"not a PNG file", "bad signature"}},
      {"jpeg.png", std::string("\xff\xd8\xff\xe0\x00\x10JFIF\x00", 11), {"not a PNG file", "bad signature"}},
      {"signature_only.png", kSig, {"corrupt or truncated PNG data"}},
      {"truncated_header.png", good.substr(0, 20), {"corrupt or truncated PNG data"}},
      {"truncated_data.png", good.substr(0, good.size() / 2), {"corrupt or truncated PNG data"}},
      {"bad_crc.png", bad_crc, {"corrupt or truncated PNG data"}},
      {"bad_deflate.png", bad_zlib, {"corrupt or truncated PNG data"}},
      {"zero_width.png", kSig + ihdr(0, 16, 8, 6) + chunk("IEND", ""), {"corrupt or truncated PNG data"}},
      {"huge.png", kSig + ihdr(100000, 100000, 8, 6) + chunk("IDAT", "\x78\x01") + chunk("IEND", ""), {"image too large (100000x100000 px", "at most 16384"}},
      // Within the size limit, but 2 bytes of data cannot hold 16384² pixels: refused
      // before the gigabyte of pixels is allocated.
      {"claims_16k.png", kSig + ihdr(16384, 16384, 16, 6) + chunk("IDAT", "\x78\x01") + chunk("IEND", ""),
       {"truncated or corrupt PNG: its header claims 16384x16384 px", "holds only 2 bytes of image data"}},
      {"no_alpha.png", png(8, 8, 2, disc), {"the image has no alpha channel (RGB)"}},
      {"transparent.png", png(16, 16, 6, [](int, int) { return 0; }), {"no opaque pixels above alpha threshold 0.5", "16x16"}},
      {"faint.png", png(16, 16, 6, [](int, int) { return 100; }), {"no opaque pixels above alpha threshold 0.5"}},
  };
}

}  // namespace

TEST_CASE("bad-input corpus: PNG sprites that cannot be imported say why", "[bad_input][png]") {
  const fs::path dir = tmp_dir("png");
  for (const PngCase& c : png_cases()) {
    DYNAMIC_SECTION(c.name) {
      const fs::path p = dir / c.name;
      write_bytes(p, c.bytes);
      std::vector<std::string> parts = c.expect;
      parts.push_back(p.string());
      check_message(input_error([&] { (void)import_png_alpha(p); }), parts);
      // The same bytes from memory, with the name given.
      const auto* b = reinterpret_cast<const unsigned char*>(c.bytes.data());
      check_message(input_error([&] { (void)import_png_alpha(std::span(b, c.bytes.size()), "sprite"); }), {"sprite: "});
    }
  }
  check_message(input_error([&] { (void)import_png_alpha(dir / "missing.png"); }), {"missing.png: no such file"});
  check_message(input_error([&] { (void)import_png_alpha(dir); }), {"is a directory, not a PNG file"});
  PngImportOptions bad;
  bad.alpha_threshold = 1.5;
  write_bytes(dir / "ok.png", png(32, 32, 6, disc));
  check_message(input_error([&] { (void)import_png_alpha(dir / "ok.png", bad); }), {"bad option: the alpha threshold must be in (0, 1)"});
  CHECK_NOTHROW(import_png_alpha(dir / "ok.png"));
}

TEST_CASE("bad-input corpus: missing, corrupt, huge or empty textures are refused, not embedded", "[bad_input][png]") {
  const fs::path dir = tmp_dir("texture");
  const std::string good = png(32, 32, 6, disc);
  const auto check = [](const std::string& bytes) {
    return check_png_texture(std::span(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size()), "tex.png");
  };
  CHECK(check(good) == std::array<int, 2>{32, 32});
  CHECK(check(png(8, 8, 2, disc)) == std::array<int, 2>{8, 8});  // a texture needs no alpha
  check_message(input_error([&] { check(""); }), {"tex.png: the texture is not a PNG file (the file is empty)"});
  check_message(input_error([&] { check("GIF89a......"); }), {"tex.png: the texture is not a PNG file (bad signature)"});
  check_message(input_error([&] { check(good.substr(0, good.size() / 2)); }), {"tex.png: the texture is corrupt or truncated PNG data"});
  check_message(input_error([&] { check(kSig + ihdr(100000, 20, 8, 6) + chunk("IDAT", "\x78\x01") + chunk("IEND", "")); }), {"tex.png: the texture"});
  const std::string claims_16k = kSig + ihdr(16384, 16384, 8, 6) + chunk("IDAT", "\x78\x01") + chunk("IEND", "");
  check_message(input_error([&] { check(claims_16k); }), {"tex.png (texture): truncated or corrupt PNG", "16384x16384"});

  // glTF export reads the scene's texture: every broken one is named, no file is written.
  Scene scene = load_scene(fs::path(HSI_TESTS_DIR) / "fuzz" / "corpus_fuzz_scene" / "square_hole.json");
  scene.base_dir = dir;
  scene.cage = build_cage(scene.shape, scene.cage_options);
  FrameFile frames;
  frames.cage = *scene.cage;
  for (double t : {0.0, 1.0}) frames.frames.push_back({t, true, true, true, 0, 2.0, identity_map(frames.cage)});
  for (const auto& [name, bytes] : std::vector<std::pair<std::string, std::string>>{
           {"empty.png", ""}, {"half.png", good.substr(0, good.size() / 2)}, {"text.png", "not a png"}, {"missing.png", "-"}}) {
    DYNAMIC_SECTION("glTF texture " << name) {
      if (name != "missing.png") write_bytes(dir / name, bytes);
      scene.texture = name;
      const fs::path out = dir / (name + ".glb");
      check_message(input_error([&] { write_glb(out, scene, frames); }), {(dir / name).string()});
      CHECK_FALSE(fs::exists(out));
      CHECK_FALSE(fs::exists(out.string() + ".tmp"));
    }
  }
  scene.texture = "good.png";
  write_bytes(dir / "good.png", good);
  CHECK_NOTHROW(write_glb(dir / "good.glb", scene, frames));
#ifdef HSI_TEST_VK_IMAGE
  // The renderer's texture reader.
  for (const std::string name : {"empty.png", "half.png", "text.png", "missing.png"})
    check_message(input_error([&] { (void)read_png(dir / name); }), {(dir / name).string()});
  write_bytes(dir / "huge.png", kSig + ihdr(100000, 100000, 8, 6) + chunk("IDAT", "\x78\x01") + chunk("IEND", ""));
  check_message(input_error([&] { (void)read_png(dir / "huge.png"); }), {"huge.png", "100000 x 100000"});
  write_bytes(dir / "claims_16k.png", claims_16k);
  check_message(input_error([&] { (void)read_png(dir / "claims_16k.png"); }), {"claims_16k.png: truncated or corrupt PNG"});
#endif
}

// ---- Frames files (.hsif) and baked files (.hsib): damaged at every byte -------------

namespace {

// A small valid sequence: three identity frames over a square with a hole.
struct SmallFiles {
  Shape shape;
  FrameFile frames;
  std::string hsif, hsib;
  SmallFiles() {
    Scene scene = load_scene(fs::path(HSI_TESTS_DIR) / "fuzz" / "corpus_fuzz_scene" / "square_hole.json");
    shape = scene.shape;
    frames.cage = build_cage(scene.shape, scene.cage_options);
    for (double t : {0.0, 0.5, 1.0}) frames.frames.push_back({t, true, t != 0.5, true, 3, 2.0, identity_map(frames.cage)});
    hsif = encode_frames(frames);
    hsib = encode_baked(shape, frames);
  }
};

}  // namespace

TEST_CASE("bad-input corpus: frames files truncated at every byte or damaged are refused", "[bad_input][frames]") {
  const SmallFiles F;
  REQUIRE_NOTHROW(decode_frames(F.hsif, "seq.hsif"));
  for (size_t cut = 0; cut < F.hsif.size(); ++cut) {
    const std::string msg = input_error([&] { (void)decode_frames(F.hsif.substr(0, cut), "seq.hsif"); });
    INFO("cut at " << cut << ": " << msg);
    REQUIRE(msg.rfind("seq.hsif: ", 0) == 0);
    CHECK((msg.find("truncated") != std::string::npos || (cut < 4 && msg.find("magic") != std::string::npos)));
  }
  check_message(input_error([&] { (void)decode_frames(F.hsif + "x", "seq.hsif"); }), {"seq.hsif", "trailing bytes"});
  std::string v = F.hsif;
  v[4] = 9;
  check_message(input_error([&] { (void)decode_frames(v, "seq.hsif"); }), {"unsupported frames version 9"});
  std::string nan = F.hsif;
  const double bad = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(nan.data() + 16, &bad, 8);  // the first cage vertex's x
  check_message(input_error([&] { (void)decode_frames(nan, "seq.hsif"); }), {"non-finite cage vertex in loop 0"});
  // On disk: a missing file and a directory.
  const fs::path dir = tmp_dir("frames");
  check_message(input_error([&] { (void)read_frames(dir / "none.hsif"); }), {"none.hsif: cannot open the frames file"});
}

TEST_CASE("bad-input corpus: baked files truncated at every byte or with any byte flipped are refused", "[bad_input][baked]") {
  const SmallFiles F;
  const std::string& b = F.hsib;
  auto open = [](const std::string& bytes, std::string& msg) {
    hsib_sequence* s = nullptr;
    char error[256] = "unset";
    const hsib_status st = hsib_open_memory(bytes.data(), bytes.size(), &s, error, sizeof error);
    msg = error;
    if (st == HSIB_OK) hsib_close(s);
    else CHECK(s == nullptr);
    return st;
  };
  std::string msg;
  REQUIRE(open(b, msg) == HSIB_OK);
  for (size_t cut = 0; cut < b.size(); ++cut) {
    const hsib_status st = open(b.substr(0, cut), msg);
    INFO("cut at " << cut << ": " << msg);
    // The magic is checked first: a cut inside it is "not a baked file".
    CHECK((st == HSIB_ERROR_TRUNCATED || (cut < 4 && st == HSIB_ERROR_FORMAT)));
    CHECK((msg.find("truncated") != std::string::npos || (cut < 4 && msg.find("not an hsi baked sequence") != std::string::npos)));
  }
  for (size_t i = 0; i < b.size(); ++i) {
    std::string c = b;
    c[i] = static_cast<char>(c[i] ^ 0x01);
    const hsib_status st = open(c, msg);
    INFO("bit flipped in byte " << i << ": " << msg);
    CHECK(st != HSIB_OK);
    CHECK_FALSE(msg.empty());
  }
  // On disk: missing, empty, a directory.
  const fs::path dir = tmp_dir("baked");
  hsib_sequence* s = nullptr;
  char error[256];
  CHECK(hsib_open_file((dir / "none.hsib").c_str(), &s, error, sizeof error) == HSIB_ERROR_IO);
  CHECK_THAT(error, Catch::Matchers::Contains("none.hsib: cannot open"));
  write_bytes(dir / "empty.hsib", "");
  CHECK(hsib_open_file((dir / "empty.hsib").c_str(), &s, error, sizeof error) != HSIB_OK);
  CHECK_THAT(error, Catch::Matchers::Contains("empty.hsib"));
  CHECK(hsib_open_file(dir.c_str(), &s, error, sizeof error) != HSIB_OK);
  CHECK(s == nullptr);
}

TEST_CASE("bad-input corpus: writers leave no partial file that looks complete", "[bad_input]") {
  const SmallFiles F;
  const fs::path dir = tmp_dir("writers");
  // A frame that does not fit the cage: the baker and the frames writer refuse it and write nothing.
  FrameFile bad = F.frames;
  bad.frames[1].map.phi.conservativeResize(3);
  check_message(input_error([&] { write_baked(dir / "seq.hsib", F.shape, bad); }), {"frame 1"});
  CHECK_FALSE(fs::exists(dir / "seq.hsib"));
  CHECK_THROWS(write_frames(dir / "seq.hsif", bad));
  CHECK_FALSE(fs::exists(dir / "seq.hsif"));
  // A folder that cannot be written: the message names the path and the system's reason.
  check_message(input_error([&] { write_file_atomic(dir / "no" / "such" / "dir" / "x.json", "{}"); }),
                {"x.json: cannot write: No such file or directory"});
  for (const auto& e : fs::directory_iterator(dir)) FAIL("left behind: " << e.path());
}
