// Small DOM and number helpers shared by the run and bench pages.

export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === undefined || value === null) continue;
    if (key === 'class') node.className = value;
    else if (key === 'text') node.textContent = value;
    else if (key.startsWith('on')) node.addEventListener(key.slice(2), value);
    else node.setAttribute(key, value);
  }
  for (const child of children.flat()) {
    if (child === undefined || child === null || child === false) continue;
    node.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return node;
}

/// A figure as people read it: 4 significant digits, no trailing noise.
export function fmt(value) {
  if (typeof value === 'number') {
    if (!Number.isFinite(value)) return String(value);
    if (Number.isInteger(value)) return value.toLocaleString('en-US');
    const a = Math.abs(value);
    if (a !== 0 && (a < 1e-3 || a >= 1e6)) return value.toExponential(3);
    return String(Number(value.toPrecision(4)));
  }
  if (typeof value === 'boolean') return value ? 'yes' : 'no';
  if (value === null || value === undefined) return '—';
  if (Array.isArray(value)) {
    if (value.length > 8) return `${value.length} values: ${value.slice(0, 6).map(fmt).join(', ')}, …`;
    return '[' + value.map(fmt).join(', ') + ']';
  }
  return String(value);
}

export function bytes(n) {
  if (n >= 1 << 30) return (n / (1 << 30)).toFixed(2) + ' GiB';
  if (n >= 1 << 20) return (n / (1 << 20)).toFixed(1) + ' MiB';
  if (n >= 1 << 10) return (n / (1 << 10)).toFixed(1) + ' KiB';
  return n + ' B';
}

export function seconds(s) {
  if (s >= 120) return (s / 60).toFixed(1) + ' min';
  if (s >= 10) return s.toFixed(1) + ' s';
  if (s >= 0.01) return s.toFixed(2) + ' s';
  return (s * 1000).toFixed(2) + ' ms';
}

/// Little-endian binary arrays, shipped as base64.
export function decode(base64, Type) {
  const text = atob(base64);
  const raw = new Uint8Array(text.length);
  for (let i = 0; i < text.length; ++i) raw[i] = text.charCodeAt(i);
  return new Type(raw.buffer);
}

export function section(id, title, ...children) {
  return el('section', { id }, el('h2', { text: title }), ...children);
}

export function table(headers, rows, numeric = []) {
  return el('table', {},
    el('thead', {}, el('tr', {}, headers.map((h) => el('th', { text: h })))),
    el('tbody', {}, rows.map((row) => el('tr', {}, row.map((cell, i) =>
      el('td', { class: numeric.includes(i) ? 'num' : null }, cell instanceof Node ? cell : fmt(cell)))))));
}

/// "shape_mse_mm2" -> "shape mse mm2".
export function words(key) {
  return key.replace(/_/g, ' ');
}
