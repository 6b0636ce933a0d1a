// The gizmo: three.js's TransformControls on a pivot at the active handle group's centre. Moving it streams
// drags to the server, one frame in flight (the newest transform waits for the previous frame), and letting go
// sends the release. Typed transforms and mirrored groups go through the same drags.
import * as THREE from '../three/build/three.module.js';
import { TransformControls } from '../three/examples/jsm/controls/TransformControls.js';
import { $, studio } from './shared.js';

// A 4x4 as the server reads it: 16 numbers, row by row.
export function rowsOf(matrix) {
  const e = matrix.elements; // column-major
  return [e[0], e[4], e[8], e[12], e[1], e[5], e[9], e[13], e[2], e[6], e[10], e[14], 0, 0, 0, 1];
}

export function matrixOfRows(rows) {
  const m = new THREE.Matrix4();
  if (rows) m.set(...rows);
  return m;
}

// The reflection about the plane through `point` with normal axis `axis` (0, 1, 2).
export function mirrorMatrix(axis, point) {
  const n = new THREE.Vector3().setComponent(axis, 1);
  const r = new THREE.Matrix4().set(
    1 - 2 * n.x * n.x, -2 * n.x * n.y, -2 * n.x * n.z, 0,
    -2 * n.y * n.x, 1 - 2 * n.y * n.y, -2 * n.y * n.z, 0,
    -2 * n.z * n.x, -2 * n.z * n.y, 1 - 2 * n.z * n.z, 0,
    0, 0, 0, 1);
  const to = new THREE.Matrix4().makeTranslation(point.x, point.y, point.z);
  const from = new THREE.Matrix4().makeTranslation(-point.x, -point.y, -point.z);
  return to.multiply(r).multiply(from);
}

export class Gizmo {
  constructor(view, connection) {
    this.view = view;
    this.connection = connection;
    this.pivot = new THREE.Object3D();
    view.overlay.add(this.pivot);
    this.controls = new TransformControls(view.camera, view.canvas);
    this.controls.setSize(0.8);
    view.overlay.add(this.controls);
    this.pivotRest = new THREE.Matrix4(); // the pivot's matrix with the group at rest
    this.group = -1;
    this.mirror = null; // {group, matrix}: the other group's transform is the mirror image of this one's
    this.controls.addEventListener('change', () => view.requestRender());
    this.controls.addEventListener('objectChange', () => {
      if (!this.controls.dragging) return;
      this.pivot.updateMatrixWorld(true);
      this.drag(new THREE.Matrix4().multiplyMatrices(this.pivot.matrixWorld, new THREE.Matrix4().getInverse(this.pivotRest)));
    });
    this.controls.addEventListener('dragging-changed', (event) => {
      this.onDragging(event.value);
      if (!event.value) this.release();
    });
    this.onDragging = () => {};
  }

  get dragging() { return this.controls.dragging; }

  // The centroid of group g's points at rest.
  centre(g) {
    const c = new THREE.Vector3();
    let count = 0;
    const code = studio.labelCodes.first_handle + g;
    for (let i = 0; i < studio.n; ++i) if (studio.labels[i] === code) {
      c.x += studio.rest[3 * i]; c.y += studio.rest[3 * i + 1]; c.z += studio.rest[3 * i + 2]; ++count;
    }
    return c.divideScalar(Math.max(count, 1));
  }

  transformOf(g) {
    return matrixOfRows(studio.state && studio.state.transforms[g]);
  }

  attach(g) {
    if (g < 0 || !studio.labels) return;
    const c = this.centre(g);
    this.pivotRest = new THREE.Matrix4().makeTranslation(c.x, c.y, c.z);
    this.pivot.matrix.multiplyMatrices(this.transformOf(g), this.pivotRest);
    this.pivot.matrix.decompose(this.pivot.position, this.pivot.quaternion, this.pivot.scale);
    this.pivot.updateMatrixWorld(true);
    this.controls.attach(this.pivot);
    this.controls.setMode(document.querySelector('input[name=gizmo]:checked').value);
    this.group = g;
    studio.activeGroup = g;
    this.view.requestRender();
  }

  detach() {
    this.controls.detach();
    this.view.requestRender();
  }

  // Group g's transform (relative to rest) set to T: one drag frame (with the mirrored group's, if any).
  drag(T, group = this.group) {
    const command = { type: 'drag', group, matrix: rowsOf(T), seq: ++studio.dragSeq };
    if (this.mirror && this.mirror.source === group) {
      const M = this.mirror.matrix;
      const mirrored = new THREE.Matrix4().multiplyMatrices(M, T).multiply(M);
      command.also = [{ group: this.mirror.group, matrix: rowsOf(mirrored) }];
    }
    studio.pending = command;
    studio.lastDrag = command.matrix;
    this.flush();
  }

  flush() {
    if (studio.inFlight || !studio.pending) return;
    studio.inFlight = true;
    this.connection.send(studio.pending);
    studio.pending = null;
  }

  // Once the last frame is in: the full diffusion and details, the next step of the history.
  release() {
    const finish = () => {
      if (studio.inFlight || studio.pending) { setTimeout(finish, 5); return; }
      studio.busy = true;
      this.connection.send({ type: 'release' });
    };
    finish();
  }
}
