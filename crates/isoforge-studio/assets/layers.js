// The layer view: the sliced G-code drawn one layer at a time from above, extrusion and
// travel apart, the layer below faint for reference.

// Splits G-code into layers of segments {x0, y0, x1, y1, extrude, skirt}. Layers start at the
// slicer's `;LAYER:n` comments; E may be absolute (M82) or relative (M83), and G92 resets.
export function parseLayers(text) {
  const layers = [];
  let current = null;
  let x = 0, y = 0, z = 0, e = 0;
  let relativeE = false, relative = false;
  let role = '';
  for (const raw of text.split('\n')) {
    const line = raw.trim();
    if (line.startsWith(';TYPE:')) { role = line.slice(6); continue; }
    if (line.startsWith(';LAYER:')) {
      current = { number: Number(line.slice(7)), z, segments: [] };
      layers.push(current);
      continue;
    }
    const code = line.split(';')[0].trim();
    if (!code) continue;
    const words = code.split(/\s+/);
    const cmd = words[0].toUpperCase();
    const arg = {};
    for (const w of words.slice(1)) arg[w[0].toUpperCase()] = Number(w.slice(1));
    if (cmd === 'M82') relativeE = false;
    else if (cmd === 'M83') relativeE = true;
    else if (cmd === 'G90') { relative = false; relativeE = false; }
    else if (cmd === 'G91') { relative = true; relativeE = true; }
    else if (cmd === 'G92') { if ('E' in arg) e = arg.E; }
    else if (cmd === 'G0' || cmd === 'G1') {
      const nx = 'X' in arg ? (relative ? x + arg.X : arg.X) : x;
      const ny = 'Y' in arg ? (relative ? y + arg.Y : arg.Y) : y;
      if ('Z' in arg) { z = relative ? z + arg.Z : arg.Z; if (current && current.segments.length === 0) current.z = z; }
      let extrude = false;
      if ('E' in arg) {
        const ne = relativeE ? e + arg.E : arg.E;
        extrude = ne > e + 1e-9;
        e = ne;
      }
      if (current && (nx !== x || ny !== y)) current.segments.push({ x0: x, y0: y, x1: nx, y1: ny, extrude, skirt: role === 'SKIRT' });
      x = nx; y = ny;
    }
  }
  return layers;
}

export class LayerView {
  constructor(canvas, slider, label) {
    this.canvas = canvas;
    this.slider = slider;
    this.label = label;
    this.layers = [];
    slider.addEventListener('input', () => this.draw());
  }

  show(gcode) {
    this.layers = parseLayers(gcode);
    // Framed on the part: the skirt around the first layer would make a small part tiny.
    let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
    for (const l of this.layers) {
      for (const s of l.segments) {
        if (!s.extrude || s.skirt) continue;
        lo = [Math.min(lo[0], s.x0, s.x1), Math.min(lo[1], s.y0, s.y1)];
        hi = [Math.max(hi[0], s.x0, s.x1), Math.max(hi[1], s.y0, s.y1)];
      }
    }
    this.box = { lo, hi };
    this.slider.max = Math.max(0, this.layers.length - 1);
    this.slider.value = Math.min(Number(this.slider.value), this.layers.length - 1);
    if (Number(this.slider.value) === 0) this.slider.value = Math.floor(this.layers.length / 2);
    this.draw();
  }

  draw() {
    const c = this.canvas, g = c.getContext('2d');
    g.fillStyle = '#fafafa';
    g.fillRect(0, 0, c.width, c.height);
    const k = Number(this.slider.value);
    const layer = this.layers[k];
    if (!layer || !Number.isFinite(this.box.lo[0])) { this.label.textContent = 'no layers'; return; }
    const { lo, hi } = this.box;
    const margin = 10;
    const scale = Math.min((c.width - 2 * margin) / Math.max(hi[0] - lo[0], 1e-6), (c.height - 2 * margin) / Math.max(hi[1] - lo[1], 1e-6));
    const px = (xx) => margin + (xx - lo[0]) * scale;
    const py = (yy) => c.height - margin - (yy - lo[1]) * scale;
    const stroke = (segments, style, width, extrude, dash) => {
      g.beginPath();
      for (const s of segments) {
        if (s.extrude !== extrude) continue;
        g.moveTo(px(s.x0), py(s.y0));
        g.lineTo(px(s.x1), py(s.y1));
      }
      g.strokeStyle = style;
      g.lineWidth = width;
      g.setLineDash(dash);
      g.stroke();
    };
    if (k > 0) stroke(this.layers[k - 1].segments, 'rgba(120,120,120,0.25)', 1, true, []);
    stroke(layer.segments, '#d84315', Math.max(1, 0.45 * scale), true, []);
    stroke(layer.segments, '#90caf9', 1, false, [4, 3]);
    g.setLineDash([]);
    const moves = layer.segments.filter((s) => s.extrude).length;
    this.label.textContent = `layer ${layer.number} of ${this.layers.length}, Z ${layer.z.toFixed(2)} mm, ${moves} extrusions`;
    this.canvas.dataset.layer = layer.number;
    this.canvas.dataset.extrusions = moves;
  }
}
