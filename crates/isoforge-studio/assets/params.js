// A control per param(..) of the script: a slider and a number box for a ranged parameter,
// a checkbox for one ranged [0, 1] with a whole default, a number box otherwise. The
// controls are rebuilt only when the declarations change, so a slider being dragged keeps
// its grip while the previews come back.

function isSwitch(p) {
  return p.range && p.range[0] === 0 && p.range[1] === 1 && Number.isInteger(p.default);
}

// A step that lands on whole numbers when everything about the parameter is whole (a
// count), else about 200 steps over the range.
function stepOf(p) {
  const [lo, hi] = p.range;
  if ([lo, hi, p.default].every(Number.isInteger) && hi - lo <= 1000) return 1;
  const raw = (hi - lo) / 200;
  const pow = Math.pow(10, Math.floor(Math.log10(raw)));
  return pow;
}

export class Params {
  constructor(box, onChange) {
    this.box = box;
    this.onChange = onChange;
    this.signature = '';
    this.values = new Map();
  }

  // [[name, value]] for the server.
  list() { return [...this.values.entries()]; }

  reset() { this.values.clear(); this.signature = ''; }

  // Declarations from the latest preview: [{name, default, value, range}].
  update(params) {
    const signature = JSON.stringify(params.map((p) => [p.name, p.default, p.range]));
    if (signature === this.signature) return;
    this.signature = signature;
    const kept = new Map();
    for (const p of params) kept.set(p.name, this.values.has(p.name) ? p.value : p.default);
    this.values = kept;
    this.box.textContent = '';
    if (params.length === 0) {
      this.box.innerHTML = '<p class="muted">The script declares no <code>param(..)</code>.</p>';
      return;
    }
    for (const p of params) this.box.appendChild(this.control(p));
  }

  control(p) {
    const row = document.createElement('div');
    row.className = 'param';
    row.dataset.name = p.name;
    const label = document.createElement('label');
    label.textContent = p.name;
    label.title = p.range ? `${p.name}: ${p.range[0]} to ${p.range[1]}, default ${p.default}` : `${p.name}, default ${p.default}`;
    row.appendChild(label);
    const value = this.values.get(p.name);
    const set = (v) => { this.values.set(p.name, v); this.onChange(); };
    if (isSwitch(p)) {
      const box = document.createElement('input');
      box.type = 'checkbox';
      box.checked = value >= 0.5;
      box.setAttribute('aria-label', p.name);
      box.addEventListener('change', () => set(box.checked ? 1 : 0));
      row.appendChild(box);
      row.appendChild(document.createElement('span'));
      return row;
    }
    const number = document.createElement('input');
    number.type = 'number';
    number.value = value;
    number.setAttribute('aria-label', `${p.name} value`);
    if (p.range) {
      const slider = document.createElement('input');
      slider.type = 'range';
      slider.min = p.range[0];
      slider.max = p.range[1];
      slider.step = stepOf(p);
      slider.value = value;
      slider.setAttribute('aria-label', p.name);
      number.min = p.range[0];
      number.max = p.range[1];
      number.step = slider.step;
      slider.addEventListener('input', () => { number.value = slider.value; set(Number(slider.value)); });
      number.addEventListener('change', () => {
        const v = Math.min(p.range[1], Math.max(p.range[0], Number(number.value)));
        if (!Number.isFinite(v)) return;
        number.value = v;
        slider.value = v;
        set(v);
      });
      row.appendChild(slider);
    } else {
      number.step = 'any';
      number.addEventListener('change', () => {
        const v = Number(number.value);
        if (Number.isFinite(v)) set(v);
      });
      row.appendChild(document.createElement('span'));
    }
    row.appendChild(number);
    return row;
  }
}
