// The deforming material: the points' shaders and the edit's per-point data. While a handle is dragged the
// vertex shader blends the sample points' motions per point (the library's diffusion, in float32,
// doc/studio.md "How a drag reaches the screen"); otherwise it draws the shown state the server sent.
import * as THREE from '../three/build/three.module.js';

const RECORDS_PER_ROW = 1024; // sample points per row of the motion texture (3 texels each)

// What a draw writes: the shaded colour, the position per point (one pixel each, read back by the test), or the
// colour with the view depth in alpha (the eye-dome lighting's input and the selection's depth pass).
export const OUTPUT = { colour: 0, positions: 1, colourDepth: 2 };

function vertexShader(maxGroups) {
  return `
precision highp float;
precision highp int;
uniform bool live;
uniform highp sampler2D records;     // per sample point 3 texels: the rows of [A - I | c]
uniform highp sampler2D collarSteps; // per collar handle point 2 texels: position step, normal step
uniform mat4 groupT[${maxGroups}];
uniform bool worldSizes;             // sprites of the point's local spacing in world units, else pointSize pixels
uniform float pointSize;
uniform float pointScale;
uniform float budgetScale;            // sprites grow while a subset is drawn, so that it still covers
uniform float pixelsPerUnit;         // pixels per world unit at view depth 1
uniform bool showSelection;
uniform int outputMode;
uniform float readbackWidth;
attribute vec3 shown;
attribute vec3 shownNormal;
attribute vec3 color;
attribute float label;
attribute float spacing;
attribute vec3 s0; attribute vec3 s1; // the stencil's sample points
attribute vec3 w0; attribute vec3 w1; // and weights
attribute float hgroup;               // exact handle group, or -1
attribute vec4 collar;                // two collar slots (-1: none) and their weights
varying vec3 vColor;
varying vec3 vNormal;
varying vec3 vPosition;
varying float vDepth;
varying float vRadius;                // the sprite's radius in world units

void accumulate(float s, float w, inout vec4 r0, inout vec4 r1, inout vec4 r2) {
  if (w == 0.0) return;
  int j = int(s);
  ivec2 at = ivec2(3 * (j % ${RECORDS_PER_ROW}), j / ${RECORDS_PER_ROW});
  r0 += w * texelFetch(records, at, 0);
  r1 += w * texelFetch(records, at + ivec2(1, 0), 0);
  r2 += w * texelFetch(records, at + ivec2(2, 0), 0);
}

void collarStep(float slot, float w, inout vec3 step, inout vec3 normalStep) {
  if (slot < 0.0) return;
  int c = int(slot);
  ivec2 at = ivec2(2 * (c % ${RECORDS_PER_ROW}), c / ${RECORDS_PER_ROW});
  step += w * texelFetch(collarSteps, at, 0).xyz;
  normalStep += w * texelFetch(collarSteps, at + ivec2(1, 0), 0).xyz;
}

void main() {
  vec3 p = shown;
  vec3 n = shownNormal;
  if (live) {
    vec4 r0 = vec4(0.0), r1 = vec4(0.0), r2 = vec4(0.0);
    accumulate(s0.x, w0.x, r0, r1, r2); accumulate(s0.y, w0.y, r0, r1, r2); accumulate(s0.z, w0.z, r0, r1, r2);
    accumulate(s1.x, w1.x, r0, r1, r2); accumulate(s1.y, w1.y, r0, r1, r2); accumulate(s1.z, w1.z, r0, r1, r2);
    vec3 rest = position;
    p = rest + vec3(dot(r0.xyz, rest) + r0.w, dot(r1.xyz, rest) + r1.w, dot(r2.xyz, rest) + r2.w);
    // The normal turns by the cofactor matrix of the blended map I + turn (rows r0..r2).
    vec3 m0 = vec3(1.0 + r0.x, r1.x, r2.x), m1 = vec3(r0.y, 1.0 + r1.y, r2.y), m2 = vec3(r0.z, r1.z, 1.0 + r2.z);
    n = normalize(normal.x * cross(m1, m2) + normal.y * cross(m2, m0) + normal.z * cross(m0, m1));
    if (hgroup >= 0.0) {
      mat4 T = groupT[int(hgroup)];
      p = (T * vec4(rest, 1.0)).xyz;
      n = mat3(T) * normal;
    } else if (collar.x >= 0.0) {
      vec3 step = vec3(0.0), normalStep = vec3(0.0);
      collarStep(collar.x, collar.z, step, normalStep);
      collarStep(collar.y, collar.w, step, normalStep);
      if (step != vec3(0.0) || normalStep != vec3(0.0)) { p += step; n = normalize(n + normalStep); }
    }
  }
  vPosition = p;
  vec3 base = color;
  if (showSelection && label >= 1.0) {
    vec3 tint = label < 2.0 ? vec3(1.0, 0.85, 0.2) : (mod(label, 2.0) < 1.0 ? vec3(1.0, 0.25, 0.2) : vec3(0.3, 0.6, 1.0));
    base = mix(base, tint, 0.55);
  }
  vColor = base;
  vNormal = normalize(normalMatrix * n);
  if (outputMode == ${OUTPUT.positions}) {
    // One pixel per point: the fragment writes the position (the test reads it back).
    float vid = float(gl_VertexID), x = mod(vid, readbackWidth), y = floor(vid / readbackWidth);
    gl_Position = vec4((x + 0.5) / readbackWidth * 2.0 - 1.0, (y + 0.5) / readbackWidth * 2.0 - 1.0, 0.0, 1.0);
    gl_PointSize = 1.0;
    vDepth = 0.0;
    return;
  }
  vec4 viewPosition = modelViewMatrix * vec4(p, 1.0);
  vDepth = -viewPosition.z;
  gl_Position = projectionMatrix * viewPosition;
  // Perspective-correct: a sprite covers its point's spacing around it at any zoom.
  gl_PointSize = worldSizes ? clamp(budgetScale * pointScale * spacing * pixelsPerUnit / max(vDepth, 1e-6), 1.0, 256.0) : pointSize;
  vRadius = worldSizes ? 0.5 * budgetScale * pointScale * spacing : 0.0;
}`;
}

const fragmentShader = `
precision highp float;
uniform int outputMode;
uniform bool worldSizes;
uniform mat4 projectionMatrix;
varying vec3 vColor;
varying vec3 vNormal;
varying vec3 vPosition;
varying float vDepth;
varying float vRadius;
void main() {
  if (outputMode == ${OUTPUT.positions}) { gl_FragColor = vec4(vPosition, 1.0); return; }
  float depth = vDepth;
  if (worldSizes) {
    // Round sprites, each a dome towards the eye: where neighbours overlap the nearer dome wins pixel by pixel,
    // so that the depth (and the eye-dome lighting on it) is smooth instead of stepped at every sprite's rim.
    vec2 c = 2.0 * gl_PointCoord - 1.0;
    float r2 = dot(c, c);
    if (r2 > 1.0) discard;
    depth -= vRadius * (1.0 - r2);
    vec4 clip = projectionMatrix * vec4(0.0, 0.0, -depth, 1.0);
    gl_FragDepth = 0.5 * clip.z / clip.w + 0.5;
  } else {
    gl_FragDepth = gl_FragCoord.z;
  }
  float light = 0.3 + 0.7 * abs(vNormal.z);
  gl_FragColor = vec4(vColor * light, outputMode == ${OUTPUT.colourDepth} ? depth : 1.0);
}`;

function emptyTexture(width) {
  const t = new THREE.DataTexture(new Float32Array(4 * width), width, 1, THREE.RGBAFormat, THREE.FloatType);
  t.needsUpdate = true;
  return t;
}

export class DeformingMaterial {
  constructor(maxGroups) {
    this.maxGroups = maxGroups;
    this.material = new THREE.ShaderMaterial({
      vertexShader: vertexShader(maxGroups), fragmentShader,
      uniforms: {
        live: { value: false }, records: { value: emptyTexture(3) }, collarSteps: { value: emptyTexture(2) },
        groupT: { value: Array.from({ length: maxGroups }, () => new THREE.Matrix4()) },
        worldSizes: { value: true }, pointSize: { value: 2 }, pointScale: { value: 1 }, budgetScale: { value: 1 }, pixelsPerUnit: { value: 1 },
        showSelection: { value: true }, outputMode: { value: OUTPUT.colour }, readbackWidth: { value: 1 },
      },
    });
    this.stencils = null; // the edit's per-point data, once prepared
  }

  get uniforms() { return this.material.uniforms; }

  set live(value) { this.material.uniforms.live.value = value; }

  // The server's preparation (its 'renderer' message): each movable point's stencil (6 sample points and
  // weights), its exact handle group and its collar entries, as vertex attributes; textures for the motions.
  prepare(geometry, n, header, a) {
    const Index = a.stencil_samples.constructor;
    const s0 = new Index(3 * n), s1 = new Index(3 * n), w0 = new Float32Array(3 * n), w1 = new Float32Array(3 * n);
    const hgroup = new Int8Array(n).fill(-1), collar = new Float32Array(4 * n).fill(-1);
    const m = a.movable.length ? a.stencil_samples.length / a.movable.length : 6;
    if (m > 6) throw new Error(`the page blends at most 6 sample points per point, not ${m}`);
    const samples = a.stencil_samples, weights = a.stencil_weights;
    for (let k = 0; k < a.movable.length; ++k) {
      const i = a.movable[k];
      for (let e = 0; e < m; ++e) {
        const at = 3 * i + (e % 3);
        if (e < 3) { s0[at] = samples[k * m + e]; w0[at] = weights[k * m + e]; }
        else { s1[at] = samples[k * m + e]; w1[at] = weights[k * m + e]; }
      }
      hgroup[i] = a.handle_group[k];
    }
    for (let k = 0; k < a.collar_points.length; ++k) {
      const at = 4 * a.collar_points[k];
      collar[at] = a.collar_slots[2 * k]; collar[at + 1] = a.collar_slots[2 * k + 1];
      collar[at + 2] = a.collar_weights[2 * k]; collar[at + 3] = a.collar_weights[2 * k + 1];
    }
    geometry.setAttribute('s0', new THREE.BufferAttribute(s0, 3));
    geometry.setAttribute('s1', new THREE.BufferAttribute(s1, 3));
    geometry.setAttribute('w0', new THREE.BufferAttribute(w0, 3));
    geometry.setAttribute('w1', new THREE.BufferAttribute(w1, 3));
    geometry.setAttribute('hgroup', new THREE.BufferAttribute(hgroup, 1));
    geometry.setAttribute('collar', new THREE.BufferAttribute(collar, 4));
    const sampleCount = header.sample_points;
    const rows = Math.ceil(sampleCount / RECORDS_PER_ROW);
    this.uniforms.records.value = new THREE.DataTexture(new Float32Array(4 * 3 * RECORDS_PER_ROW * rows),
      3 * RECORDS_PER_ROW, rows, THREE.RGBAFormat, THREE.FloatType);
    const collarRows = Math.max(1, Math.ceil(header.collar_handles / RECORDS_PER_ROW));
    this.uniforms.collarSteps.value = new THREE.DataTexture(new Float32Array(4 * 2 * RECORDS_PER_ROW * collarRows),
      2 * RECORDS_PER_ROW, collarRows, THREE.RGBAFormat, THREE.FloatType);
    this.stencils = { samples: sampleCount, collar: header.collar_handles, movable: a.movable };
  }

  // One drag frame: the records of all sample points, the groups' transforms, the collar handle points' steps.
  frame(f, groups) {
    const { samples, collar } = this.stencils;
    const records = this.uniforms.records.value;
    records.image.data.set(f.subarray(0, 12 * samples));
    records.needsUpdate = true;
    for (let g = 0; g < groups; ++g) {
      const r = f.subarray(12 * (samples + g), 12 * (samples + g + 1));
      this.uniforms.groupT.value[g].set(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9], r[10], r[11], 0, 0, 0, 1);
    }
    const steps = f.subarray(12 * (samples + groups));
    const texture = this.uniforms.collarSteps.value.image.data;
    for (let c = 0; c < collar; ++c) {
      texture.set(steps.subarray(6 * c, 6 * c + 3), 8 * c);
      texture.set(steps.subarray(6 * c + 3, 6 * c + 6), 8 * c + 4);
    }
    this.uniforms.collarSteps.value.needsUpdate = true;
    this.live = true;
  }

  unprepare() {
    this.stencils = null;
    this.live = false;
  }
}
