// The studio page: wires the editor, the parameters, the 3D view, slicing, export and
// printing to the server. The preview is refined in steps: a coarse mesh after every edit
// (one request in flight; edits made meanwhile are folded into the next), then a finer
// one, dropped as soon as another edit comes.
import { ApiError, download, fetchPreview, getJSON, postJSON, sendJSON } from './api.js';
import { Editor } from './editor.js';
import { LayerView } from './layers.js';
import { Params } from './params.js';
import { PrintPanel } from './print.js';
import { View3D } from './view3d.js';

// The coarse step's depth; the server's COARSE_DEPTH says why this one.
const COARSE_DEPTH = 6;
// Typing pauses this long before a preview: a half-typed word is rarely a model.
const TYPING_PAUSE_MS = 120;

const $ = (id) => document.getElementById(id);

const studio = {
  name: null,
  version: null,
  savedText: '',
  job: 0,
  doneJob: -1,
  coarseBusy: false,
  again: false,
  fine: null,
  latencies: [],
  facts: null,
  sliced: null,
  profiles: [],
};
window.studio = studio;

function say(text, bad) {
  $('busy').textContent = text;
  $('busy').style.color = bad ? '#ff8a80' : '';
}

const editor = new Editor($('editor'), $('gutter'), $('problem'), () => {
  updateFileState();
  clearTimeout(studio.typing);
  studio.typingPending = true;
  studio.typing = setTimeout(() => { studio.typingPending = false; edited(); }, TYPING_PAUSE_MS);
});
const params = new Params($('params'), () => edited());
const view = new View3D($('view'));
const layers = new LayerView($('layers'), $('layer'), $('layer-label'));
const printer = new PrintPanel({
  port: $('port'), refresh: $('ports-refresh'), fake: $('fake-start'), start: $('print-start'),
  resume: $('print-resume'), pause: $('print-pause'), cancel: $('print-cancel'),
  progress: $('print-progress'), state: $('print-state'), detail: $('print-detail'),
}, () => ensureSliced(), say);

function model() {
  return { name: studio.name, text: editor.text, params: params.list() };
}

function fineDepth() { return Number($('fine-depth').value); }

// An edit happened (text, slider, file reloaded): start its coarse preview now, or fold it
// into the next one if a coarse preview is on its way.
function edited() {
  // Numbered by the clock (microseconds), not from 1: the server drops requests older than
  // the newest it has seen, and a reloaded page must not look older than its last life.
  studio.job = Math.max(studio.job + 1, Math.round((performance.timeOrigin + performance.now()) * 1000));
  performance.mark(`edit-${studio.job}`);
  if (studio.fine) { studio.fine.abort(); studio.fine = null; }
  if (studio.coarseBusy) { studio.again = true; return; }
  coarse();
}

async function coarse() {
  const job = studio.job;
  studio.coarseBusy = true;
  studio.again = false;
  $('refine').textContent = 'meshing…';
  let ok = false;
  try {
    const p = await fetchPreview({ ...model(), depth: COARSE_DEPTH, job });
    performance.mark(`fetched-${job}`);
    show(p, job);
    ok = true;
  } catch (e) {
    failed(e);
  }
  studio.coarseBusy = false;
  studio.doneJob = job;
  if (studio.again) { coarse(); return; }
  if (ok && fineDepth() > COARSE_DEPTH) refine(job);
  else $('refine').textContent = '';
}

async function refine(job) {
  const controller = new AbortController();
  studio.fine = controller;
  $('refine').textContent = `refining to depth ${fineDepth()}…`;
  try {
    const p = await fetchPreview({ ...model(), depth: fineDepth(), job }, controller.signal);
    if (job === studio.job) show(p, job);
    $('refine').textContent = '';
  } catch (e) {
    if (job === studio.job) failed(e);
  }
  if (studio.fine === controller) studio.fine = null;
}

function failed(e) {
  if (e.name === 'AbortError' || (e instanceof ApiError && e.status === 409)) return;
  $('refine').textContent = '';
  if (e instanceof ApiError && e.body.problem) {
    editor.showProblem(e.body.problem);
    document.body.dataset.problemLine = e.body.problem.line || '';
  } else {
    editor.showProblem({ message: e.message });
  }
}

function show(p, job) {
  const { header, positions, indices } = p;
  editor.clearProblem();
  document.body.dataset.problemLine = '';
  params.update(header.params);
  view.setMesh(positions, indices);
  showFacts(header.facts);
  const depth = header.facts.depth;
  if (depth === COARSE_DEPTH) performance.mark(`uploaded-${job}`);
  view.drawNow(() => {
    // On screen: the animation frame after the drawing. The parts: the request (script,
    // mesh, transfer), the upload (normals, buffers, controls), and the frames.
    if (depth === COARSE_DEPTH) {
      const m = performance.measure(`coarse-preview-${job}`, `edit-${job}`);
      const part = (a, b) => performance.measure(`${a}-${b}-${job}`, `${a}-${job}`, `${b}-${job}`).duration;
      performance.mark(`shown-${job}`);
      studio.latencies.push({
        job, ms: m.duration, triangles: header.facts.triangles, meshMs: header.facts.seconds * 1000,
        requestMs: part('edit', 'fetched'), uploadMs: part('fetched', 'uploaded'), frameMs: part('uploaded', 'shown'),
      });
    }
    document.body.dataset.previewJob = job;
    document.body.dataset.previewDepth = depth;
  });
}

function fmt(v, digits = 3) {
  return Number(v).toPrecision(digits > 0 ? Math.max(digits, 1) : 3);
}

function showFacts(f) {
  studio.facts = f;
  $('fact-triangles').textContent = f.triangles.toLocaleString('en');
  $('fact-triangles').dataset.value = f.triangles;
  $('fact-vertices').textContent = f.vertices.toLocaleString('en');
  $('fact-volume').textContent = `${fmt(f.volume, 5)} mm³`;
  $('fact-volume').dataset.value = f.volume;
  $('fact-area').textContent = `${fmt(f.area, 5)} mm²`;
  if (f.bounds) {
    const size = [0, 1, 2].map((k) => (f.bounds[1][k] - f.bounds[0][k]).toFixed(2));
    $('fact-size').textContent = `${size.join(' × ')} mm`;
  }
  const closed = f.watertight && f.manifold;
  $('fact-closed').textContent = closed ? 'closed, manifold' : `${f.watertight ? 'closed' : 'OPEN'}, ${f.manifold ? 'manifold' : 'NOT manifold'}`;
  $('fact-closed').className = closed ? '' : 'bad';
  $('fact-depth').textContent = `${f.depth} (${(f.seconds * 1000).toFixed(0)} ms)`;
  // As `isoforge mesh` notes it: 2 % or more of the triangles join the two sides of parts
  // thinner than about two cells, which this depth does not resolve.
  const thin = f.thin_triangles || 0;
  const share = f.triangles > 0 ? thin / f.triangles : 0;
  $('fact-thin').textContent = share >= 0.02
    ? `${(100 * share).toFixed(1)} % of the mesh: a finer depth resolves them`
    : thin > 0 ? `${(100 * share).toFixed(2)} % of the mesh` : 'none';
  $('fact-thin').className = share >= 0.02 ? 'bad' : '';
}

function updateFileState() {
  const dirty = editor.text !== studio.savedText;
  $('file-state').textContent = dirty ? 'unsaved changes' : 'saved';
  document.title = `${dirty ? '• ' : ''}${studio.name} – isoforge studio`;
}

async function open(name) {
  const f = await getJSON(`/api/file?name=${encodeURIComponent(name)}`);
  studio.name = f.name;
  studio.version = f.version;
  studio.savedText = f.text;
  editor.text = f.text;
  $('file').value = f.name;
  $('disk-banner').hidden = true;
  params.reset();
  view.fitted = false;
  studio.sliced = null;
  updateFileState();
  edited();
}

async function save(force) {
  try {
    const text = editor.text;
    const r = await (await sendJSON('PUT', '/api/file', { name: studio.name, text, base: studio.version, force })).json();
    studio.version = r.version;
    studio.savedText = text;
    $('disk-banner').hidden = true;
    updateFileState();
    say(`saved ${studio.name}`);
  } catch (e) {
    if (e instanceof ApiError && e.status === 409
      && confirm(`${e.message}.\n\nOverwrite it with the text in the editor?`)) return save(true);
    say(e.message, true);
  }
}

// Another editor changed a file: take it if ours has no unsaved edits, else ask.
function changedOnDisk(event) {
  if (event.name !== studio.name || event.version === studio.version) return;
  if (editor.text === studio.savedText) open(studio.name);
  else $('disk-banner').hidden = false;
}

function profile() {
  return studio.profiles.find((p) => p.id === $('profile').value);
}

async function ensureSliced() {
  if (studio.sliced && studio.sliced.text === editor.text
    && JSON.stringify(studio.sliced.params) === JSON.stringify(params.list())
    && studio.sliced.profile === $('profile').value) return studio.sliced.file;
  return slice();
}

async function slice() {
  const p = profile();
  if (!p || p.technology !== 'fdm') { say('choose a filament (FDM) printer profile to slice to G-code', true); return null; }
  say('slicing…');
  $('slice-state').textContent = 'slicing…';
  try {
    const request = { ...model(), profile: p.id };
    const r = await postJSON('/api/slice', request);
    studio.sliced = { text: request.text, params: request.params, profile: p.id, file: r.file };
    $('fact-time').textContent = clockText(r.seconds);
    $('fact-filament').textContent = `${(r.filament_mm / 1000).toFixed(2)} m (${r.filament_g.toFixed(1)} g)`;
    $('slice-state').textContent = `${r.layers} layers → ${r.file}`;
    $('layers-box').hidden = false;
    layers.show(r.gcode);
    printer.checkResumable(r.file);
    say(`sliced into ${r.file}`);
    return r.file;
  } catch (e) {
    $('slice-state').textContent = '';
    if (e instanceof ApiError && e.body.problem) editor.showProblem(e.body.problem);
    say(e.message, true);
    return null;
  }
}

function clockText(seconds) {
  const s = Math.round(seconds);
  const h = Math.floor(s / 3600), m = Math.floor(s / 60) % 60;
  return h ? `${h} h ${m} min` : `${m} min ${s % 60} s`;
}

async function exportFile() {
  const format = $('export-format').value;
  say(`exporting ${format.toUpperCase()}…`);
  try {
    const r = await download('/api/export', { ...model(), format, depth: fineDepth(), profile: $('profile').value });
    say(`downloaded ${r.name} (${r.size.toLocaleString('en')} bytes)`);
    document.body.dataset.exported = r.name;
  } catch (e) { say(e.message, true); }
}

function listen() {
  const events = new EventSource('/api/events');
  events.onmessage = (m) => {
    const event = JSON.parse(m.data);
    if (event.type === 'file') changedOnDisk(event);
    else if (event.type === 'print') {
      printer.show(event.status);
    }
  };
}

async function start() {
  const session = await getJSON('/api/session');
  for (const f of session.files.includes(session.model) ? session.files : [session.model, ...session.files]) {
    const o = document.createElement('option');
    o.value = o.textContent = f;
    $('file').appendChild(o);
  }
  studio.profiles = session.profiles;
  for (const p of session.profiles) {
    const o = document.createElement('option');
    o.value = p.id;
    o.textContent = `${p.name} (${p.plate[0]}×${p.plate[1]} mm, ${p.technology})`;
    $('profile').appendChild(o);
  }
  for (let d = COARSE_DEPTH; d <= session.maxDepth; d++) {
    const o = document.createElement('option');
    o.value = o.textContent = d;
    $('fine-depth').appendChild(o);
  }
  $('fine-depth').value = 8;
  $('profile').addEventListener('change', () => { const p = profile(); if (p) view.setPlate(p.plate); });
  if (profile()) view.setPlate(profile().plate);
  $('file').addEventListener('change', () => open($('file').value));
  $('save').addEventListener('click', () => save(false));
  document.addEventListener('keydown', (e) => {
    if ((e.ctrlKey || e.metaKey) && e.key === 's') { e.preventDefault(); save(false); }
  });
  $('disk-reload').addEventListener('click', () => open(studio.name));
  $('disk-keep').addEventListener('click', () => { $('disk-banner').hidden = true; });
  $('fit').addEventListener('click', () => view.fit());
  $('edges').addEventListener('change', () => view.setEdges($('edges').checked));
  $('fine-depth').addEventListener('change', () => edited());
  $('export').addEventListener('click', exportFile);
  $('slice').addEventListener('click', slice);
  listen();
  await printer.refreshPorts();
  try {
    await open(session.model);
  } catch (e) {
    // A new model: start from a small example.
    studio.name = session.model;
    studio.version = null;
    studio.savedText = '';
    editor.text = 'bounds([-12, -12, -12], [12, 12, 12]);\nlet r = param("r", 10, 2, 12);\nSphere(r)\n';
    updateFileState();
    edited();
  }
  document.body.dataset.ready = '1';
}

start().catch((e) => say(e.message, true));
