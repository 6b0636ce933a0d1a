// Selection: the brush, the lasso and the connected-part click, in screen space. Only what is seen is taken
// unless X-ray is on: a depth pass gives the nearest surface at each pixel, and a point counts as seen when it
// lies within a few local spacings of it.
import { $, showError, studio } from './shared.js';

const SPACINGS_BEHIND = 2; // how far behind the seen surface (its sprites bulge a spacing towards the eye) a point still counts as on it

function insideLasso(path, x, y) {
  let inside = false;
  for (let a = 0, b = path.length - 1; a < path.length; b = a++) {
    const [xa, ya] = path[a], [xb, yb] = path[b];
    if ((ya > y) !== (yb > y) && x < ((xb - xa) * (y - ya)) / (yb - ya) + xa) inside = !inside;
  }
  return inside;
}

// A spacing for every point: the server's local spacing when it sent one, else the spacing of that many points
// spread evenly over the bounding box's faces (about the surface a scan of that box has).
export function spacingOf(i) {
  if (studio.spacing) return studio.spacing[i];
  return studio.fallbackSpacing;
}

export function fallbackSpacing(size, n) {
  const area = 2 * (size[0] * size[1] + size[1] * size[2] + size[2] * size[0]);
  return Math.sqrt(area / Math.max(n, 1));
}

export class Selection {
  constructor(view, connection) {
    this.view = view;
    this.connection = connection;
    this.stroke = null;
    const canvas = view.canvas;
    canvas.addEventListener('pointerdown', (event) => this.down(event));
    canvas.addEventListener('pointermove', (event) => this.move(event));
    canvas.addEventListener('pointerup', () => this.up());
    // Shift + wheel: the brush radius (caught before the orbit's zoom sees the wheel).
    $('view').addEventListener('wheel', (event) => {
      if (!event.shiftKey) return;
      event.preventDefault();
      event.stopPropagation();
      const input = $('brush-size');
      const delta = (event.deltaY || event.deltaX) > 0 ? -1 : 1;
      const radius = Math.round(Number(input.value) * (1 + 0.1 * delta));
      input.value = Math.min(Number(input.max), Math.max(Number(input.min), radius + delta));
      this.drawBrush(this.lastPointer);
    }, { capture: true, passive: false });
    canvas.addEventListener('pointerleave', () => { this.lastPointer = null; this.drawBrush(null); });
    for (const input of document.querySelectorAll('input[name=tool]')) input.addEventListener('change', () => this.drawOverlay());
  }

  tool() { return document.querySelector('input[name=tool]:checked').value; }
  target() { return document.querySelector('input[name=target]:checked').value; }
  group() { return Math.max(0, $('group').selectedIndex); }

  canvasPoint(event) {
    const r = this.view.canvas.getBoundingClientRect();
    return [event.clientX - r.left, event.clientY - r.top];
  }

  // Which points the tools may take: all of them in X-ray, else those within a few spacings of the surface seen
  // at their pixel (off-screen points never).
  visibleMask(screen, depth) {
    const n = studio.n, visible = new Uint8Array(n);
    const { width, height } = this.view;
    if ($('xray').checked) {
      for (let i = 0; i < n; ++i) visible[i] = depth[i] > 0 ? 1 : 0;
      return visible;
    }
    const pass = this.view.depthPass();
    const perUnit = this.view.pixelsPerUnit(height);
    for (let i = 0; i < n; ++i) {
      const x = Math.floor(screen[2 * i]), y = Math.floor(screen[2 * i + 1]);
      if (!(x >= 0 && y >= 0 && x < width && y < height) || depth[i] <= 0) continue;
      // The nearest surface at the pixel and the 8 around it: a point of the far side seen through a pixel-wide
      // gap between the near side's sprites is behind its neighbours' surface.
      let seen = Infinity;
      for (let dy = -1; dy <= 1; ++dy) {
        for (let dx = -1; dx <= 1; ++dx) {
          const px = x + dx, py = y + dy;
          if (px < 0 || py < 0 || px >= width || py >= height) continue;
          const d = pass.depth[py * width + px];
          if (d > 0 && d < seen) seen = d;
        }
      }
      // Two pixels' footprint at that depth added: a pixel's depth is a sprite's, not the point's own, and the
      // nearest of the window may lie a pixel away on a slope.
      const tolerance = SPACINGS_BEHIND * spacingOf(i) + 2 * depth[i] / perUnit;
      if (seen < Infinity && depth[i] <= seen + tolerance) visible[i] = 1;
    }
    return visible;
  }

  begin(event) {
    const { screen, depth } = this.view.projectAll();
    return { screen, depth, visible: this.visibleMask(screen, depth) };
  }

  down(event) {
    const tool = this.tool();
    if (tool === 'orbit' || !studio.geometry || event.button !== 0) return;
    const target = this.target();
    if (target === 'handle' && $('group').options.length === 0) { showError('make a handle group first (New handle group)'); return; }
    if (tool === 'connected') { this.pickConnected(event, target); return; }
    const t0 = performance.now();
    this.stroke = Object.assign(this.begin(event), {
      kind: tool, target, erase: $('erase').checked, group: this.group(), mask: new Uint8Array(studio.n),
      path: [this.canvasPoint(event)],
    });
    studio.timings.push(['stroke start', t0, performance.now()]);
    this.view.canvas.setPointerCapture(event.pointerId);
    if (this.stroke.kind === 'brush') this.paintUnder(this.canvasPoint(event));
  }

  move(event) {
    this.lastPointer = this.canvasPoint(event);
    if (!this.stroke) { this.drawBrush(this.lastPointer); return; } // the brush's outline, or none
    this.stroke.path.push(this.canvasPoint(event));
    if (this.stroke.kind === 'brush') this.paintUnder(this.canvasPoint(event));
    else this.drawOverlay();
  }

  up() {
    if (!this.stroke) return;
    const s = this.stroke;
    this.stroke = null;
    this.drawOverlay();
    if (s.kind === 'lasso') {
      for (let i = 0; i < studio.n; ++i) {
        if (s.visible[i] && insideLasso(s.path, s.screen[2 * i], s.screen[2 * i + 1])) s.mask[i] = 1;
      }
    }
    const indices = [];
    for (let i = 0; i < studio.n; ++i) if (s.mask[i]) indices.push(i);
    this.connection.sendIndices({ type: 'select', target: s.target, mode: s.erase ? 'erase' : 'add', group: s.group }, indices);
  }

  previewLabel(s) {
    const c = studio.labelCodes;
    if (s.erase) return s.target === 'roi' ? c.fixed : c.roi;
    return s.target === 'roi' ? c.roi : c.first_handle + s.group;
  }

  paintUnder([x, y]) {
    const s = this.stroke;
    const radius = Number($('brush-size').value);
    const r2 = radius * radius, screen = s.screen, label = studio.geometry.getAttribute('label');
    const preview = this.previewLabel(s);
    for (let i = 0; i < studio.n; ++i) {
      const dx = screen[2 * i] - x, dy = screen[2 * i + 1] - y;
      if (dx * dx + dy * dy <= r2 && s.visible[i] && !s.mask[i]) {
        s.mask[i] = 1;
        label.array[i] = preview;
      }
    }
    label.needsUpdate = true;
    this.drawBrush([x, y]);
    this.view.requestRender();
  }

  // The connected part of the neighbour graph under the click: the seen point nearest to it, within the brush.
  pickConnected(event, target) {
    const [x, y] = this.canvasPoint(event);
    const { screen, visible } = this.begin(event);
    const radius = Number($('brush-size').value);
    let best = -1, bestD = radius * radius;
    for (let i = 0; i < studio.n; ++i) {
      if (!visible[i]) continue;
      const dx = screen[2 * i] - x, dy = screen[2 * i + 1] - y, d = dx * dx + dy * dy;
      if (d <= bestD) { bestD = d; best = i; }
    }
    if (best < 0) { showError('no point under the click'); return; }
    studio.busy = true;
    this.connection.send({ type: 'select_connected', target, mode: $('erase').checked ? 'erase' : 'add',
                           group: this.group(), seed: best });
  }

  // The outlines are SVG over the view (a 2D canvas kept a cleared lasso on the screen in headless Chromium).
  drawBrush(at) {
    this.drawOverlay();
    const circle = $('brush-outline');
    if (!at || this.tool() !== 'brush') { circle.setAttribute('visibility', 'hidden'); return; }
    circle.setAttribute('cx', at[0]);
    circle.setAttribute('cy', at[1]);
    circle.setAttribute('r', $('brush-size').value);
    circle.setAttribute('visibility', 'visible');
  }

  drawOverlay() {
    const s = this.stroke;
    const lasso = s && s.kind === 'lasso' && s.path.length >= 2;
    $('lasso-outline').setAttribute('points', lasso ? s.path.map((p) => p.join(',')).join(' ') : '');
    if (!s && this.tool() !== 'brush') $('brush-outline').setAttribute('visibility', 'hidden');
  }
}
