// Talking to the studio's server: JSON calls, the binary preview, downloads.
// Every request is same-origin and carries the access cookie set on the first load.

export class ApiError extends Error {
  constructor(status, body) {
    super(body && body.error ? body.error : `HTTP ${status}`);
    this.status = status;
    this.body = body || {};
  }
}

async function check(response) {
  if (response.ok) return response;
  let body = null;
  try { body = await response.json(); } catch (_) { /* not JSON */ }
  throw new ApiError(response.status, body);
}

export async function getJSON(url) {
  return (await check(await fetch(url))).json();
}

export async function sendJSON(method, url, body, signal) {
  const response = await fetch(url, {
    method,
    headers: { 'content-type': 'application/json' },
    body: JSON.stringify(body),
    signal,
  });
  return check(response);
}

export async function postJSON(url, body, signal) {
  return (await sendJSON('POST', url, body, signal)).json();
}

// The preview's layout (see preview.rs): "ISOP", header length, JSON header, vertex and
// triangle counts, then positions (f32) and indices (u32), all aligned to 4 bytes.
export function decodePreview(buffer) {
  const view = new DataView(buffer);
  const magic = String.fromCharCode(...new Uint8Array(buffer, 0, 4));
  if (magic !== 'ISOP') throw new Error('not a preview');
  const headerLength = view.getUint32(4, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 8, headerLength)));
  let at = 8 + headerLength;
  const vertices = view.getUint32(at, true);
  const triangles = view.getUint32(at + 4, true);
  at += 8;
  const positions = new Float32Array(buffer, at, vertices * 3);
  const indices = new Uint32Array(buffer, at + vertices * 12, triangles * 3);
  return { header, positions, indices };
}

export async function fetchPreview(body, signal) {
  const response = await sendJSON('POST', '/api/preview', body, signal);
  return decodePreview(await response.arrayBuffer());
}

// Saves a response as a file through the browser's own download.
export async function download(url, body) {
  const response = await sendJSON('POST', url, body);
  const blob = await response.blob();
  const disposition = response.headers.get('content-disposition') || '';
  const match = /filename="([^"]+)"/.exec(disposition);
  const name = match ? match[1] : 'download';
  const link = document.createElement('a');
  link.href = URL.createObjectURL(blob);
  link.download = name;
  document.body.appendChild(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(link.href), 60000);
  return { name, size: blob.size };
}
