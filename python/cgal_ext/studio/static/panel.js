// The side panel: its controls send the commands, and the server's state shows in it.
import * as THREE from '../three/build/three.module.js';
import { matrixOfRows, mirrorMatrix } from './gizmo.js';
import { $, showError, status, studio } from './shared.js';
import { UP_AXES } from './view.js';

// The up axis chosen per scan, in a cookie: cookies ignore the port, local storage would not (each studio
// session has its own port, so its own storage).
const UP_COOKIE = 'cgal_ext_studio_up';

function upChoices() {
  const cookie = document.cookie.split('; ').find((c) => c.startsWith(UP_COOKIE + '='));
  try { return cookie ? JSON.parse(decodeURIComponent(cookie.slice(UP_COOKIE.length + 1))) : {}; } catch { return {}; }
}

export function rememberedUp(scan) {
  const axis = upChoices()[scan];
  return axis in UP_AXES ? axis : null;
}

function rememberUp(scan, axis) {
  const choices = upChoices();
  delete choices[scan];
  choices[scan] = axis;
  const names = Object.keys(choices);
  for (const name of names.slice(0, Math.max(0, names.length - 40))) delete choices[name]; // the cookie stays small
  document.cookie = `${UP_COOKIE}=${encodeURIComponent(JSON.stringify(choices))}; path=/; max-age=31536000; SameSite=Strict`;
}

export class Panel {
  constructor({ view, connection, gizmo, material, onColors }) {
    this.view = view;
    this.connection = connection;
    this.gizmo = gizmo;
    this.material = material;
    const send = (command) => connection.send(command);
    const busy = (command) => { studio.busy = true; send(command); };

    $('open').onclick = () => send({ type: 'load', path: $('file').value });
    $('fit').onclick = () => view.fit();
    for (const name of ['front', 'top', 'side']) $(`view-${name}`).onclick = () => view.preset(name);
    $('up-axis').onchange = () => {
      view.setUp($('up-axis').value);
      if (studio.state && studio.state.scan) rememberUp(studio.state.scan, view.up);
      view.preset('front');
    };
    $('color').onchange = () => {
      if ($('color').value === 'plain') onColors();
      else send({ type: 'colors', by: $('color').value });
    };
    $('show-selection').onchange = () => { material().uniforms.showSelection.value = $('show-selection').checked; view.requestRender(); };
    $('point-size').oninput = () => { material().uniforms.pointScale.value = Number($('point-size').value); view.requestRender(); };
    $('edl').onchange = () => { view.edl.enabled = $('edl').checked; view.requestRender(); };
    $('edl-strength').oninput = () => { view.edl.strength = Number($('edl-strength').value); view.requestRender(); };

    $('new-group').onclick = () => { send({ type: 'new_group' }); $('paint-handle').checked = true; };
    $('group').onchange = () => { if (material().stencils) gizmo.attach($('group').selectedIndex); this.showPivot(); };
    $('invert').onclick = () => send({ type: 'invert' });
    $('clear').onclick = () => send({ type: 'clear' });
    const target = () => document.querySelector('input[name=target]:checked').value;
    $('grow').onclick = () => busy({ type: 'grow', target: target(), group: Math.max(0, $('group').selectedIndex) });
    $('shrink').onclick = () => busy({ type: 'shrink', target: target(), group: Math.max(0, $('group').selectedIndex) });
    $('load-edit').onclick = () => send({ type: 'load_edit', path: $('edit-file').value });
    for (const input of document.querySelectorAll('input[name=tool]')) input.addEventListener('change', () => this.updateOrbit());

    for (const key of ['order', 'rotations', 'strength_distance']) $(key).onchange = () => send({ type: 'settings', [key]: $(key).value });
    $('edit-start').onclick = () => busy({ type: 'preprocess' });
    for (const input of document.querySelectorAll('input[name=gizmo]')) {
      input.onchange = () => { gizmo.controls.setMode(input.value); view.requestRender(); };
    }
    $('commit').onclick = () => busy({ type: 'commit' });
    $('fill').onclick = () => busy({ type: 'fill' });
    $('undo').onclick = () => busy({ type: 'undo' });
    $('redo').onclick = () => busy({ type: 'redo' });
    $('details-s').oninput = () => { $('details-value').textContent = Number($('details-s').value).toFixed(1); };
    $('details-preview').onclick = () => busy({ type: 'details', mode: $('details-mode').value, s: Number($('details-s').value) });
    $('details-apply').onclick = () => busy({ type: 'details', mode: $('details-mode').value, s: Number($('details-s').value), apply: true });
    $('save').onclick = () => {
      $('save-status').textContent = 'saving…';
      send({ type: 'save', name: $('save-name').value });
    };

    $('typed-apply').onclick = () => this.applyTyped();
    $('typed-centre').onclick = () => this.showPivot(true);
    $('mirror').onchange = () => this.updateMirror();
    $('mirror-group').onchange = () => this.updateMirror();
    $('mirror-axis').onchange = () => this.updateMirror();

    gizmo.onDragging = (dragging) => { this.updateOrbit(); view.setDragging(dragging); };
    $('budget').onchange = () => { view.budget = Math.max(0, Math.round(Number($('budget').value) || 0)); view.applyBudget(); };
    window.addEventListener('keydown', (event) => {
      if (event.target.tagName === 'INPUT' && !['checkbox', 'radio', 'range'].includes(event.target.type)) return;
      if (event.ctrlKey && event.key === 'z') $('undo').click();
      if (event.ctrlKey && event.key === 'y') $('redo').click();
    });
  }

  updateOrbit() {
    const tool = document.querySelector('input[name=tool]:checked').value;
    this.view.setOrbitEnabled(tool === 'orbit' && !this.gizmo.dragging);
  }

  // The scan's up axis: the one chosen for it before, else the default for its shape.
  startView(scan, size) {
    const axis = rememberedUp(scan) || this.view.constructor.defaultUp(size);
    $('up-axis').value = axis;
    this.view.setUp(axis);
    this.view.preset('front');
  }

  onState(m) {
    studio.state = m;
    studio.busy = false;
    const files = $('file');
    if (m.files && files.options.length !== m.files.length) {
      files.innerHTML = '';
      for (const f of m.files) files.add(new Option(f, f));
    }
    if (m.scan) files.value = m.scan;
    for (const select of [$('group'), $('mirror-group')]) {
      if (select.options.length === m.groups) continue;
      const active = Math.min(Math.max(select.selectedIndex, 0), m.groups - 1);
      select.innerHTML = '';
      for (let g = 0; g < m.groups; ++g) select.add(new Option(`handle group ${g}`, g));
      select.selectedIndex = m.groups ? (select.id === 'group' ? Math.max(active, m.groups - 1) : active) : -1;
    }
    for (const key of ['order', 'rotations', 'strength_distance']) $(key).value = m.settings[key];
    $('history').textContent = `step ${m.step} of ${m.steps}`;
    this.showHistory(m);
    if (m.preprocessed || m.groups === 0) this.showWarnings(null);
    const level = m.level_of_detail;
    const points = level ? `its level of detail, ${m.points} of ${level.scan_points} points` : `${m.points} points`;
    status(m.scan ? `${m.scan}: ${points}, region ${m.region}, ${m.groups} handle group(s)` +
                    (m.preprocessed ? ', ready to drag' : '') : 'no scan open');
    $('progress-bar').style.width = '0';
    const material = this.material();
    if (!m.preprocessed) {
      this.gizmo.detach();
      if (material) material.unprepare();
      studio.prepared = false;
    } else if (material && material.stencils && !this.gizmo.dragging) {
      this.gizmo.attach($('group').selectedIndex);
    }
    this.showPivot();
    this.updateMirror();
    this.view.requestRender();
  }

  // The undo list: each step of the history, the shown one marked.
  showHistory(m) {
    const list = $('history-list');
    list.innerHTML = '';
    (m.history || []).forEach((kind, k) => {
      const item = document.createElement('li');
      item.textContent = k === 0 ? 'the scan' : kind;
      if (k === m.step) item.className = 'current';
      list.appendChild(item);
    });
    if ('committable' in m) $('commit').disabled = !m.committable && !(m.step > 0);
    // A level of detail saves one edit, carried to the whole scan: what would change its base is off.
    const level = Boolean(m.level_of_detail);
    for (const id of ['commit', 'fill', 'details-apply']) {
      if (level) $(id).disabled = true;
      else if (id !== 'commit') $(id).disabled = false;
      $(id).title = level ? 'a level of detail saves one edit, carried to every point of the scan' : '';
    }
  }

  // The server's word before an edit that would not make sense (each warning with its remedy, or edit anyway),
  // or after a release that swung the region (with an undo).
  showWarnings(warnings) {
    studio.warnings = warnings;
    const box = $('warnings');
    box.innerHTML = '';
    if (!warnings || !warnings.length) return;
    if (warnings.every((w) => w.kind === 'swing')) {
      for (const w of warnings) {
        const line = document.createElement('div');
        line.textContent = w.message;
        box.appendChild(line);
      }
      const undo = document.createElement('button');
      undo.textContent = 'Undo the drag';
      undo.id = 'undo-swing';
      undo.onclick = () => { this.showWarnings(null); studio.busy = true; this.connection.send({ type: 'undo' }); };
      box.appendChild(undo);
      return;
    }
    for (const w of warnings) {
      const line = document.createElement('div');
      line.textContent = w.message;
      box.appendChild(line);
      if (w.kind === 'island') {
        const grow = document.createElement('button');
        grow.textContent = `Grow the region around handle group ${w.group}`;
        grow.id = `grow-around-${w.group}`;
        grow.onclick = () => { this.showWarnings(null); studio.busy = true; this.connection.send({ type: 'grow_region_around', group: w.group }); };
        box.appendChild(grow);
      }
    }
    const anyway = document.createElement('button');
    anyway.textContent = 'Edit anyway';
    anyway.id = 'edit-anyway';
    anyway.onclick = () => { this.showWarnings(null); studio.busy = true; this.connection.send({ type: 'preprocess', force: true }); };
    box.appendChild(anyway);
  }

  // ---- typed transforms -----------------------------------------------------------------------------------

  // The pivot field: the active group's centre at rest (as the gizmo's), unless the user typed another.
  showPivot(reset = false) {
    const g = $('group').selectedIndex;
    if (g < 0 || !studio.labels) return;
    if (!reset && $('typed-pivot').dataset.group === String(g) && $('typed-pivot').value) return;
    const c = this.gizmo.centre(g);
    $('typed-pivot').value = [c.x, c.y, c.z].map((v) => Number(v.toPrecision(6))).join(' ');
    $('typed-pivot').dataset.group = String(g);
  }

  static vector(id) {
    const values = $(id).value.trim().split(/[\s,]+/).map(Number);
    if (values.length !== 3 || !values.every(Number.isFinite)) throw new Error(`${id.replace('typed-', '')}: three numbers`);
    return new THREE.Vector3(...values);
  }

  // The typed transform: turn by the angle about the axis through the pivot, then move by the translation.
  typedMatrix() {
    const t = Panel.vector('typed-translation'), axis = Panel.vector('typed-axis'), pivot = Panel.vector('typed-pivot');
    const angle = Number($('typed-angle').value);
    if (!Number.isFinite(angle)) throw new Error('angle: a number of degrees');
    const R = new THREE.Matrix4();
    if (angle !== 0) {
      if (axis.length() === 0) throw new Error('axis: not zero');
      R.makeRotationAxis(axis.normalize(), (angle * Math.PI) / 180);
    }
    return new THREE.Matrix4().makeTranslation(pivot.x + t.x, pivot.y + t.y, pivot.z + t.z)
      .multiply(R).multiply(new THREE.Matrix4().makeTranslation(-pivot.x, -pivot.y, -pivot.z));
  }

  // Applied as a drag: one frame, then the release.
  applyTyped() {
    if (!this.material() || !this.material().stencils) { showError('prepare the edit first (Edit)'); return; }
    let T;
    try { T = this.typedMatrix(); } catch (error) { showError(`typed transform: ${error.message}`); return; }
    const g = $('group').selectedIndex;
    this.gizmo.drag(T, g);
    this.gizmo.release();
  }

  // ---- mirrored editing -----------------------------------------------------------------------------------

  // The mirror plane: through the centre of the two groups' centres, across the chosen axis.
  updateMirror() {
    const on = $('mirror').checked, g = $('group').selectedIndex, h = $('mirror-group').selectedIndex;
    this.gizmo.mirror = null;
    if (!on || g < 0 || h < 0 || g === h || !studio.labels) return;
    const axis = Number($('mirror-axis').value);
    const centre = this.gizmo.centre(g).add(this.gizmo.centre(h)).multiplyScalar(0.5);
    this.gizmo.mirror = { source: g, group: h, matrix: mirrorMatrix(axis, centre) };
  }
}
