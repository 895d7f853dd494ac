// The page of a run folder or a bench folder, built from the JSON that
// `spec2fab` inlined into report.html (element #spec2fab-data; wall times in
// #spec2fab-timing, kept apart so the rest is byte-identical across reruns).
import css from './report.css';
import { el, fmt, bytes, seconds, section, table, words } from './util.js';
import { lineChart } from './charts.js';
import { viewerSection } from './viewer.js';
import { benchPage } from './bench.js';

// What the headline figures mean; any other figure is shown by its name.
const MEANINGS = {
  ssim: 'structural similarity of the cast image to the goal (1 = same)',
  psnr_db: 'peak signal-to-noise ratio of the cast image (dB)',
  relative_rmse: 'RMS of image minus goal over the goal’s RMS',
  initial_ssim: 'SSIM at the start (flat surface)',
  delta_e00: 'CIEDE2000 colour difference between goal and achieved (1 ≈ just noticeable)',
  low_pass_delta_e00: 'mean ΔE00 after a blur: what the eye sees from afar',
  in_gamut: 'over pixels whose goal is printable',
  out_of_gamut: 'over pixels whose goal lies outside the printable gamut',
  shape_mse_mm2: 'mean squared distance of the probes from their goal positions',
  probe_rms_mm: 'RMS distance of the probes from their goal positions',
  nodes_pruned: 'subtrees branch and bound pruned by the bound',
  leaves_evaluated: 'complete assignments simulated',
  leaves_evaluated_total: 'stacks branch and bound simulated, all columns',
  fraction_of_exhaustive: 'share of an exhaustive search branch and bound needed',
  exhaustive: 'assignments an exhaustive search would simulate',
  profile_relative_rms: 'RMS of achieved minus goal scattering profile, relative to the goal',
  final_error: 'the tuner’s error at its end',
  initial_error: 'the tuner’s error at its start',
};
const HEADLINE = ['ssim', 'psnr_db', 'relative_rmse', 'mean', 'p95', 'low_pass_delta_e00', 'shape_mse_mm2', 'probe_rms_mm',
  'nodes_pruned', 'leaves_evaluated', 'fraction_of_exhaustive', 'profile_relative_rms', 'margin_mm', 'mass_change_g', 'shell_mm', 'mass_saved_fraction', 'stress_p99_mpa'];
const SHARED = new Set(['spec2fab_version', 'experiment', 'translator', 'seed', 'inputs', 'tree', 'material_census', 'tuning',
  'fabrication', 'files', 'warnings']);

function data(id) {
  const node = document.getElementById(id);
  return node ? JSON.parse(node.textContent) : null;
}

/// Figures of one section, flattened: [dotted path, value].
function flatten(value, prefix, out) {
  if (value && typeof value === 'object' && !Array.isArray(value)) {
    for (const [k, v] of Object.entries(value)) flatten(v, prefix ? `${prefix}.${k}` : k, out);
  } else {
    out.push([prefix, value]);
  }
  return out;
}

function headlineCards(result, meanings) {
  const cards = [];
  // A subset's figure equal to its whole's (ΔE00 over the out-of-gamut
  // pixels when every pixel is out of gamut) is shown once, named by the
  // shorter path: leaf=value -> [index in cards, path].
  const shown = new Map();
  const label = (path) => path.replace(/^headline\./, 'print, traced independently.').split('.').slice(-3).map(words).join(' › ');
  const card = (path, v) => el('div', { class: 'card', title: meaningOf(path, meanings) },
    el('div', { class: 'v', text: fmt(v) }), el('div', { class: 'k', text: label(path) }));
  // "headline" (what the exported print casts, traced independently) first;
  // within a section, the figures in HEADLINE's order.
  const sections = Object.entries(result).sort(([a], [b]) => (b === 'headline') - (a === 'headline'));
  const order = (path) => HEADLINE.indexOf(path.split('.').pop());
  for (const [name, value] of sections) {
    if (SHARED.has(name)) continue;
    for (const [path, v] of flatten(value, name, []).sort(([a], [b]) => order(a) - order(b))) {
      const leaf = path.split('.').pop();
      if (!HEADLINE.includes(leaf) || typeof v !== 'number') continue;
      if (path.includes('initial') || path.includes('nearest_only')) continue;
      // The simulator's own trace of the written surface (a check of the
      // file) would sit beside the headline's independent trace as a third,
      // differently made SSIM; it stays under Figures.
      if (path.includes('surface_stl')) continue;
      const twin = shown.get(`${leaf}=${v}`);
      if (twin) {
        if (path.split('.').length < twin[1].split('.').length) cards[twin[0]] = card(path, v), twin[1] = path;
        continue;
      }
      if (cards.length >= 8) continue;
      shown.set(`${leaf}=${v}`, [cards.length, path]);
      cards.push(card(path, v));
    }
  }
  // Every fabricated print's cost and time (fabrication.print), whatever the translator.
  const print = result.fabrication?.print;
  if (print && typeof print.cost_usd === 'number') {
    cards.push(el('div', { class: 'card', title: meaningOf('fabrication.print.cost_usd', meanings) },
      el('div', { class: 'v', text: `$${print.cost_usd.toFixed(2)}` }), el('div', { class: 'k', text: 'material cost' })));
  }
  if (print && typeof print.print_hours === 'number') {
    const minutes = Math.round(print.print_hours * 60);
    cards.push(el('div', { class: 'card', title: meaningOf('fabrication.print.print_hours', meanings) },
      el('div', { class: 'v', text: `${Math.floor(minutes / 60)} h ${String(minutes % 60).padStart(2, '0')} min` }),
      el('div', { class: 'k', text: `print time (${print.time_model} model)` })));
  }
  return cards;
}

/// A figure's meaning: its own documented one (the run's field docs), else its
/// nearest documented ancestor's, else the page's own words for common leaves.
function meaningOf(path, meanings) {
  const parts = path.split('.');
  for (let n = parts.length; n > 0; --n) {
    const text = meanings[parts.slice(0, n).join('.')];
    if (text) return n === parts.length ? text : `${parts.slice(n).join(' ')}: ${text}`;
  }
  return MEANINGS[parts[parts.length - 1]] || '';
}

function figuresSection(result, meanings) {
  const blocks = [];
  for (const [name, value] of Object.entries(result)) {
    if (SHARED.has(name) || value === null || typeof value !== 'object') continue;
    const rows = flatten(value, '', []).map(([path, v]) => [path, v, meaningOf(`${name}.${path}`, meanings)]);
    blocks.push(el('h3', { text: name }), table(['figure', 'value', 'meaning'], rows, [1]));
  }
  const tuners = result.tuning?.tuners;
  if (tuners) blocks.push(el('h3', { text: 'tuners' }), table(['tuner', 'final error'], tuners.map((t) => [t.name, t.final_error]), [1]));
  // A tuner that weighs several terms: each one's error, its rule, and its share of the tuner's error.
  const terms = (tuners || []).flatMap((t) => (t.terms || []).map((term) => [t.name, term.name,
    `${term.simulator} · ${term.metric}`, term.error,
    term.at_most !== undefined ? `at most ${term.at_most}` : `weight ${term.weight}`, term.contribution]));
  if (terms.length) {
    blocks.push(el('h3', { text: 'tuner terms' }),
      table(['tuner', 'term', 'simulator · metric', 'error', 'rule', 'contribution'], terms, [3, 5]));
  }
  const phases = result.tuning?.phases;
  if (phases) {
    blocks.push(el('h3', { text: 'tuning phases' }), table(['phase', 'tuner runs', 'evaluations', 'error at start (sum)', 'at end'],
      phases.map((p) => [p.name, p.tuner_runs, p.evaluations, p.sum_initial_error, p.sum_final_error]), [1, 2, 3, 4]));
  }
  return section('figures', 'Figures', ...blocks);
}

function picturesSection(images) {
  if (!images.length) return null;
  const figures = images.map((image) => el('figure', {},
    image.data ? el('img', { src: image.data, alt: image.name, width: image.width ? String(image.width) : null,
      height: image.height ? String(image.height) : null })
      : el('a', { href: image.name, text: `open ${image.name}` }),
    el('figcaption', {}, el('b', { text: image.name }), ` — ${image.width} × ${image.height} px. ${image.caption || ''}`)));
  return section('pictures', 'Goal and achieved, at full resolution',
    el('p', { class: 'muted', text: 'Each picture at its own size, one screen pixel per pixel; scroll sideways for wide ones.' }),
    el('div', { class: 'pair' }, figures));
}

/// convergence.csv, as the writer summed it up: the tuner runs it holds and the first few traces.
function convergenceSection(convergence) {
  if (!convergence) return null;
  const traces = convergence.traces;
  const children = [el('p', { class: 'muted', text: `${fmt(convergence.runs)} tuner run(s) in convergence.csv` +
    (traces.length ? `; the best error so far against evaluations of ${traces.length === convergence.runs ? 'each' : `the first ${traces.length} with a trace`}.` : '; none kept a trace (each made one evaluation).') })];
  if (traces.length) {
    const values = traces.flatMap((t) => t.points.map((p) => p[1])).filter((v) => v > 0);
    const logY = values.length > 0 && Math.max(...values) / Math.min(...values) > 100;
    children.push(lineChart({ title: 'best error so far', x_label: 'evaluations', y_label: 'error', log_x: true, log_y: logY,
      series: traces.map((t) => ({ label: t.label, points: t.points.filter((p) => !logY || p[1] > 0) })) }).element);
  }
  return section('convergence', 'Convergence', ...children);
}

function censusSection(result) {
  const census = result.material_census;
  const fabricated = result.fabrication?.materials;
  if (!census && !fabricated) return null;
  const rows = [];
  for (const [name, m] of Object.entries(census?.materials || {})) {
    rows.push([name, m.volume_mm3, Number.isFinite(m.fraction) ? (100 * m.fraction).toFixed(1) + ' %' : '—']);
  }
  const children = [];
  if (rows.length) children.push(el('p', { class: 'muted', text: `Census on a ${fmt(census.voxel_mm)} mm grid.` }),
    table(['material', 'volume (mm³)', 'share'], rows, [1, 2]));
  if (fabricated) {
    const frows = Object.entries(fabricated).map(([name, m]) => [name, m.voxels, m.volume_mm3]);
    children.push(el('h3', { text: 'in the print' }), table(['material', 'print voxels', 'volume (mm³)'], frows, [1, 2]));
  }
  return section('materials', 'Material census', ...children);
}

function timingSection(timing) {
  if (!timing) return null;
  const rows = flatten(timing, '', []).filter(([, v]) => typeof v === 'number')
    .map(([k, v]) => [k, k.endsWith('seconds') || k.includes('seconds') ? seconds(v) : fmt(v)]);
  return section('timing', 'Timings', el('p', { class: 'muted', text: 'From timing.json (wall times; they vary between runs).' }),
    table(['step', 'time'], rows, [1]));
}

function inputsSection(result) {
  const inputs = result.inputs || {};
  const rows = flatten(inputs, '', []);
  return section('inputs', 'Inputs', table(['input', 'value'], rows));
}

function filesSection(files) {
  const rows = files.map((f) => [el('a', { href: f.path, text: f.path }), f.bytes === undefined ? '' : bytes(f.bytes) + (f.count ? ` in ${f.count} files` : '')]);
  return section('files', 'Files of the run',
    el('p', { class: 'muted', text: 'Beside this report in the run folder; the 3D view shows decimated copies of the meshes.' }),
    table(['file', 'size'], rows, [1]));
}

function runPage(d, timing) {
  const result = d.result;
  const images = d.images || [];
  const header = el('header', {}, el('h1', { text: `${result.experiment} — ${result.translator}` }),
    el('p', { text: `spec2fab ${result.spec2fab_version} · seed ${result.seed} · printer ${result.inputs?.printer?.name || '—'}` }));
  const sections = [];
  const lead = section('summary', 'What the run was for, and what it reached',
    el('p', { class: 'lead', text: d.purpose || '' }), el('div', { class: 'cards' }, headlineCards(result, d.meanings || {})));
  const headline = result.headline;
  if (headline?.agreement) {
    lead.append(el('p', { class: 'headline-note', text: `${headline.file}, traced by ${headline.traced_by}: ${headline.agreement}.` }));
  }
  if (d.notes?.length) lead.append(el('ul', { class: 'muted' }, d.notes.map((n) => el('li', { text: n }))));
  const warnings = timing?.warnings || [];
  if (warnings.length) {
    lead.append(el('h3', { class: 'warn', text: `warnings (${warnings.length})` }),
      el('ul', { class: 'warn' }, warnings.map((w) => el('li', { text: w }))));
  }
  sections.push(lead);
  sections.push(picturesSection(images));
  let viewer = null;
  if (d.viewer) {
    viewer = viewerSection(d.viewer, images);
    sections.push(section('view', '3D view of the print', viewer.element));
  }
  sections.push(figuresSection(result, d.meanings || {}), convergenceSection(d.convergence), censusSection(result), timingSection(timing),
    inputsSection(result), filesSection(d.files || []));
  const present = sections.filter(Boolean);
  const nav = el('nav', {}, present.map((s) => el('a', { href: '#' + s.id, text: s.querySelector('h2').textContent.split(',')[0] })));
  document.body.append(header, nav, el('main', {}, present));
  if (viewer) viewer.start();
}

function start() {
  document.head.append(el('style', { text: css }));
  const d = data('spec2fab-data');
  const timing = data('spec2fab-timing');
  try {
    if (d.kind === 'bench') benchPage(d, timing);
    else runPage(d, timing);
  } finally {
    document.body.dataset.ready = 'true';
  }
}

start();
