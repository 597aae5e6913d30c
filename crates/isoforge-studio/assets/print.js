// The print panel: ports, the fake printer, start / resume / pause / cancel, and the live
// status the server pushes as events.
import { getJSON, postJSON } from './api.js';

function clock(seconds) {
  if (seconds == null) return '–';
  const s = Math.round(seconds);
  const h = Math.floor(s / 3600), m = Math.floor(s / 60) % 60;
  return h ? `${h}h${String(m).padStart(2, '0')}m` : `${m}m${String(s % 60).padStart(2, '0')}s`;
}

export class PrintPanel {
  // `slice` returns the sliced G-code's file name (slicing first when needed).
  constructor(el, slice, say) {
    this.el = el;
    this.slice = slice;
    this.say = say;
    el.refresh.addEventListener('click', () => this.refreshPorts());
    el.fake.addEventListener('click', () => this.startFake());
    el.start.addEventListener('click', () => this.start(false));
    el.resume.addEventListener('click', () => this.start(true));
    el.pause.addEventListener('click', () => this.control(this.status && this.status.state === 'paused' ? 'resume' : 'pause'));
    el.cancel.addEventListener('click', () => this.control('cancel'));
  }

  async refreshPorts(select) {
    const ports = await getJSON('/api/ports');
    const keep = select || this.el.port.value;
    this.el.port.textContent = '';
    for (const p of ports) {
      const o = document.createElement('option');
      o.value = p.path;
      o.textContent = p.kind === 'fake' ? `${p.path} (fake printer)` : `${p.path} (${p.kind})`;
      this.el.port.appendChild(o);
    }
    if (ports.length === 0) {
      const o = document.createElement('option');
      o.value = '';
      o.textContent = 'no serial ports: start a fake printer';
      this.el.port.appendChild(o);
    }
    if (keep && ports.some((p) => p.path === keep)) this.el.port.value = keep;
  }

  async startFake() {
    try {
      const { path } = await postJSON('/api/fake-printer', {});
      await this.refreshPorts(path);
      this.say(`fake printer on ${path}`);
    } catch (e) { this.say(e.message, true); }
  }

  async checkResumable(file) {
    try {
      const r = await getJSON(`/api/print?file=${encodeURIComponent(file)}`);
      this.el.resume.hidden = !r.resumable || this.running();
      this.show(r.status);
    } catch (_) { /* no file yet */ }
  }

  running() {
    return this.status && (this.status.state === 'running' || this.status.state === 'paused');
  }

  async start(resume) {
    const port = this.el.port.value;
    if (!port) { this.say('pick a serial port, or start a fake printer', true); return; }
    try {
      const file = await this.slice();
      if (!file) return;
      let restart = false;
      for (;;) {
        try {
          const r = await postJSON('/api/print', { file, port, resume, restart });
          this.show(r.status);
          return;
        } catch (e) {
          // An unfinished job's journal would be lost: ask before starting over.
          if (e.status === 409 && !resume && !restart && /unfinished|resume/.test(e.message)
            && confirm(`${e.message}\n\nStart over from the beginning?`)) { restart = true; continue; }
          throw e;
        }
      }
    } catch (e) { this.say(e.message, true); }
  }

  async control(action) {
    try { this.show((await postJSON(`/api/print/${action}`, {})).status); } catch (e) { this.say(e.message, true); }
  }

  show(s) {
    if (!s) return;
    this.status = s;
    const el = this.el;
    const live = s.state === 'running' || s.state === 'paused';
    el.progress.value = s.percent || 0;
    el.state.textContent = s.state === 'idle' ? 'idle'
      : `${s.state}: ${(s.percent || 0).toFixed(1)}% (${s.executed} of ${s.total} commands)`;
    el.state.dataset.state = s.state;
    el.state.dataset.percent = s.percent || 0;
    const parts = [];
    if (s.layer != null) parts.push(`layer ${s.layer}${s.z != null ? ` at Z ${s.z.toFixed(2)}` : ''}`);
    if (live) parts.push(`ETA ${clock(s.eta_seconds)}`);
    if (s.hotend) parts.push(`hotend ${s.hotend[0].toFixed(0)}/${s.hotend[1].toFixed(0)} °C`);
    if (s.bed) parts.push(`bed ${s.bed[0].toFixed(0)}/${s.bed[1].toFixed(0)} °C`);
    if (s.error) parts.push(`error: ${s.error}`);
    if (s.notes && s.notes.length) parts.push(s.notes[s.notes.length - 1]);
    el.detail.textContent = parts.join(' · ');
    el.start.disabled = live;
    el.pause.disabled = !live;
    el.pause.textContent = s.state === 'paused' ? 'Resume' : 'Pause';
    el.cancel.disabled = !live;
    if (live) el.resume.hidden = true;
    else if (s.state === 'cancelled' || s.state === 'failed') el.resume.hidden = false;
    else if (s.state === 'completed') el.resume.hidden = true;
  }
}
