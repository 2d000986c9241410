// The hsi web player (web/player.html): loads a .hsib and its texture, binds the
// stored triangulation with the baked runtime (WebAssembly, hsib.js), uploads the
// basis rows once as an RGBA32F texture and draws with three.js, the vertex shader
// being shaders/hsib_playback.glsl behind its GL/WebGL2 preamble. Per frame only the
// uniforms change: hsib_blend_at_time picks the two frames and s (blending only where
// the baker certified it), hsib_gpu_uniforms fills the weights.
// &distortion=LO,HI colours the shape by its conformal distortion sigma1/sigma2 at the
// vertices (sampled, not the certificate's bound), as hsi render --overlay distortion
// --distortion-range LO HI does (its colour map, shaders/render_shade.glsl, at its
// opacity 0.85): the binding keeps derivative rows (HSIB_BIND_DERIVATIVES), uploaded
// once as a second texture, and the vertex shader calls hsib_singular_values.
// The view is hsi render's (--no-labels): the bounding box of the boundary's images
// over view_frames, fitted with a margin of max(12, 0.05 * max(w, h)) pixels.
import * as THREE from 'three';
import createHsib from './hsib.js';

const q = new URLSearchParams(location.search);
const W = parseInt(q.get('w') || '512'), H = parseInt(q.get('h') || '512');
const fixedTime = q.has('t') ? parseFloat(q.get('t')) : null;
const modes = { nearest: 0, steps: 1, blend: 2 };
const mode = modes[q.get('mode') || 'steps'];
const distortion = q.has('distortion') ? (q.get('distortion') || '1,2').split(',').map(Number) : null;

async function bytesOf(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return new Uint8Array(await r.arrayBuffer());
}
async function textOf(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return r.text();
}

async function main() {
  if (distortion && !(distortion.length === 2 && distortion[1] > distortion[0]))
    throw new Error(`distortion=${q.get('distortion')}: give LO,HI with HI > LO`);
  const M = await createHsib();
  const file = await bytesOf(q.get('hsib') || 'seq.hsib');
  const filePtr = M._malloc(file.length);
  M.HEAPU8.set(file, filePtr);
  const seq = M._hsib_web_open(filePtr, file.length);
  M._free(filePtr);
  if (!seq) throw new Error('the .hsib file does not open (see the console)');
  const frames = M._hsib_web_frame_count(seq), R = M._hsib_web_row_length(seq);
  const P = M._hsib_web_mesh_vertex_count(seq), T = M._hsib_web_mesh_triangle_count(seq);
  if (!P) throw new Error('the .hsib file carries no mesh (version 1): bake it again');
  const xyPtr = M._hsib_web_mesh_xy(seq);
  const xy = new Float32Array(M.HEAPF32.buffer, xyPtr, 2 * P).slice();
  const uv = new Float32Array(M.HEAPF32.buffer, M._hsib_web_mesh_uv(seq), 2 * P).slice();
  const tri = new Uint32Array(M.HEAPU32.buffer, M._hsib_web_mesh_triangles(seq), 3 * T).slice();
  const binding = M._hsib_web_bind(seq, xyPtr, P, distortion ? 1 : 0);
  if (!binding) throw new Error('the mesh does not bind (see the console)');

  // Rows once: T texels a vertex, 4 rows a texel, in a 2048-wide float texture (and
  // the derivative rows, 2T texels a vertex, in a second one).
  const width = 2048;
  function floatTexture(floats, fill, what) {
    const n = floats(binding, width);
    const ptr = M._malloc(4 * n);
    if (fill(binding, width, ptr) !== 0) throw new Error(`${what} failed`);
    const data = new Float32Array(M.HEAPF32.buffer, ptr, n).slice();
    M._free(ptr);
    const tex = new THREE.DataTexture(data, width, n / (4 * width), THREE.RGBAFormat, THREE.FloatType);
    tex.minFilter = tex.magFilter = THREE.NearestFilter;
    tex.needsUpdate = true;
    return tex;
  }
  const rowsTex = floatTexture(M._hsib_gpu_rows_floats, M._hsib_gpu_rows, 'hsib_gpu_rows');
  const derivativeTex = distortion ?
    floatTexture(M._hsib_gpu_derivative_rows_floats, M._hsib_gpu_derivative_rows, 'hsib_gpu_derivative_rows') : null;

  // The view: boundary vertices (edges of one triangle) mapped by the view frames.
  const edges = new Map();
  for (let k = 0; k < T; ++k)
    for (let e = 0; e < 3; ++e) {
      const a = tri[3 * k + e], b = tri[3 * k + (e + 1) % 3];
      const key = a < b ? a * P + b : b * P + a;
      edges.set(key, (edges.get(key) || 0) + 1);
    }
  const onBoundary = new Uint8Array(P);
  for (const [key, n] of edges) if (n === 1) { onBoundary[Math.floor(key / P)] = 1; onBoundary[key % P] = 1; }
  const viewFrames = q.has('view_frames') ? q.get('view_frames').split(',').map(Number) : [...Array(frames).keys()];
  const blendPtr = M._malloc(16), outPtr = M._malloc(8 * P);
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  for (const f of viewFrames) {
    M.HEAPU32.set([f, f, 0, 0], blendPtr / 4);
    M._hsib_evaluate_blend(binding, blendPtr, outPtr, 0);
    const out = new Float32Array(M.HEAPF32.buffer, outPtr, 2 * P);
    for (let v = 0; v < P; ++v)
      if (onBoundary[v]) {
        x0 = Math.min(x0, out[2 * v]); x1 = Math.max(x1, out[2 * v]);
        y0 = Math.min(y0, out[2 * v + 1]); y1 = Math.max(y1, out[2 * v + 1]);
      }
  }
  const margin = Math.max(12, 0.05 * Math.max(W, H));
  const s = Math.min((W - 2 * margin) / (x1 - x0), (H - 2 * margin) / (y1 - y0));
  const cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const camera = new THREE.OrthographicCamera(cx - W / 2 / s, cx + W / 2 / s, cy + H / 2 / s, cy - H / 2 / s, -1, 1);

  const [preamble, body, shade] = await Promise.all([textOf('hsib_preamble_gl.glsl'), textOf('hsib_playback.glsl'),
    distortion ? textOf('render_shade.glsl') : '']);
  const texture = await new THREE.TextureLoader().loadAsync(q.get('texture') || 'texture.png');
  texture.flipY = false;  // the runtime's v = 0 is the image's top row
  const uniformsPtr = M._malloc(16 * (R + 2));
  const defines = { HSIB_MAX_ROWS: R };
  const uniforms = {
    hsib_rows: { value: rowsTex },
    hsib_pose: { value: new THREE.Vector4() },
    hsib_params: { value: new THREE.Vector4() },
    hsib_weights: { value: new Float32Array(4 * R) },
    map: { value: texture },
  };
  let vertexShader = `${preamble}\n${body}\nout vec2 v_uv;\nvoid main() {\n  v_uv = uv;\n` +
    `  gl_Position = projectionMatrix * modelViewMatrix * vec4(hsib_position(HSIB_VERTEX_INDEX), 0.0, 1.0);\n}\n`;
  let fragmentShader = 'uniform sampler2D map;\nin vec2 v_uv;\nout vec4 hsib_color;\nvoid main() { hsib_color = texture(map, v_uv); }\n';
  if (distortion) {
    defines.HSIB_DERIVATIVES = 1;
    uniforms.hsib_derivative_rows = { value: derivativeTex };
    uniforms.dist_lo = { value: distortion[0] };
    uniforms.dist_inv = { value: 1 / (distortion[1] - distortion[0]) };
    // The colour-map parameter per vertex, interpolated, then clamped (as hsi render).
    vertexShader = `${preamble}\n${body}\n${shade}\nuniform float dist_lo;\nuniform float dist_inv;\nout vec2 v_uv;\n` +
      `out float kappa_t;\nvoid main() {\n  v_uv = uv;\n  vec2 sigma = hsib_singular_values(HSIB_VERTEX_INDEX);\n` +
      `  kappa_t = hsi_kappa_t(sigma.y > 0.0 ? hsib_conformal_distortion(sigma) : -1.0, dist_lo, dist_inv);\n` +
      `  gl_Position = projectionMatrix * modelViewMatrix * vec4(hsib_position(HSIB_VERTEX_INDEX), 0.0, 1.0);\n}\n`;
    fragmentShader = `precision highp float;\n${shade}\nuniform sampler2D map;\nin vec2 v_uv;\nin float kappa_t;\n` +
      'out vec4 hsib_color;\nvoid main() {\n  vec4 c = texture(map, v_uv);\n' +
      '  hsib_color = vec4(mix(c.rgb, hsi_colormap(kappa_t), 0.85), c.a);\n}\n';
  }
  const material = new THREE.ShaderMaterial({
    glslVersion: THREE.GLSL3,
    defines,
    uniforms,
    vertexShader,
    fragmentShader,
    transparent: true,
    side: THREE.DoubleSide,
  });
  const geometry = new THREE.BufferGeometry();
  const position = new Float32Array(3 * P);
  for (let v = 0; v < P; ++v) { position[3 * v] = xy[2 * v]; position[3 * v + 1] = xy[2 * v + 1]; }
  geometry.setAttribute('position', new THREE.BufferAttribute(position, 3));
  geometry.setAttribute('uv', new THREE.BufferAttribute(uv, 2));
  geometry.setIndex(new THREE.BufferAttribute(tri, 1));
  const mesh = new THREE.Mesh(geometry, material);
  mesh.frustumCulled = false;  // the shader moves the vertices
  const scene = new THREE.Scene();
  scene.add(mesh);
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(W, H);
  renderer.setClearColor(0xffffff, 1);
  document.body.appendChild(renderer.domElement);

  const t0 = M._hsib_web_frame_time(seq, 0), t1 = M._hsib_web_frame_time(seq, frames - 1);
  function draw(t) {
    M._hsib_web_blend_at_time(seq, t, mode, blendPtr);
    if (M._hsib_gpu_uniforms(seq, blendPtr, uniformsPtr) !== 0) throw new Error('hsib_gpu_uniforms failed');
    const u = new Float32Array(M.HEAPF32.buffer, uniformsPtr, 4 * (R + 2));
    material.uniforms.hsib_pose.value.fromArray(u, 0);
    material.uniforms.hsib_params.value.fromArray(u, 4);
    material.uniforms.hsib_weights.value.set(u.subarray(8));
    renderer.render(scene, camera);
  }
  if (fixedTime !== null) {
    draw(fixedTime);
    document.title = 'hsib ready';
  } else {
    const start = performance.now();
    renderer.setAnimationLoop(() => {
      const span = Math.max(t1 - t0, 1e-9);
      draw(t0 + (((performance.now() - start) / 1000 / 4) % 1) * span);  // the sequence every 4 s
    });
  }
}

main().catch((e) => {
  document.title = 'hsib error';
  document.body.textContent = `hsi web player: ${e.message}`;
  console.error(e);
});
