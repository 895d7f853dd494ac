// The page of a `spec2fab bench` folder, from its report.json: the matrix at
// a glance, per problem the convergence (median, quartile band) and runtime
// ECDF with read-outs on hover, and the fight matrix.
import { el, fmt, seconds, section, table } from './util.js';
import { lineChart } from './charts.js';

function heat(value) {
  if (value === null || value === undefined || Number.isNaN(value)) return '#f3f4f7';
  const r = Math.round(230 - 120 * value), g = Math.round(120 + 110 * value), b = 130;
  return `rgb(${r},${g},${b})`;
}

function glance(report) {
  const entrants = report.fights?.entrants || [];
  const problems = report.problems.filter((p) => p.entrants);
  const rows = problems.map((p) => [p.name, ...entrants.map((name) => {
    const e = p.entrants.find((x) => x.entrant === name);
    if (!e) return el('span', { class: 'muted', text: 'n/a' });
    const span = Math.max(1e-300, p.start_error - p.optimum);
    const relative = (e.final_error.median - p.optimum) / span;
    return el('span', { title: `median final error ${fmt(e.final_error.median)} [q1 ${fmt(e.final_error.q1)}, q3 ${fmt(e.final_error.q3)}], ` +
      `success ${Math.round(100 * e.success_rate)} %, median evaluations ${fmt(e.median_evaluations)}`, text: fmt(relative) });
  })]);
  return section('glance', 'At a glance',
    el('p', { class: 'muted', text: 'Median final error as a share of the start’s distance to the optimum (0: optimum found). Hover a cell for its quartiles, success rate and evaluations.' }),
    table(['problem', ...entrants], rows, entrants.map((_, i) => i + 1)));
}

function problemSection(p, index) {
  if (p.unavailable) return section(`p${index}`, p.name, el('p', { class: 'muted', text: `Not run in this build: ${p.unavailable}` }));
  const rows = p.entrants.map((e) => [e.entrant, e.runs, e.final_error.median, e.final_error.q1, e.final_error.q3,
    `${Math.round(e.success_rate * e.runs)}/${e.runs}`, e.median_evaluations]);
  const charts = [];
  if (p.charts?.convergence) charts.push(lineChart(p.charts.convergence).element);
  if (p.charts?.ecdf) charts.push(lineChart(p.charts.ecdf).element);
  return section(`p${index}`, p.name,
    el('p', { class: 'muted', text: `dimension ${p.dimension}, start error ${fmt(p.start_error)}, optimum ${fmt(p.optimum)}, budget ${p.budget > 0 ? p.budget : 'unlimited'} evaluations` }),
    table(['entrant', 'runs', 'final error: median', 'q1', 'q3', 'success', 'evaluations (median)'], rows, [1, 2, 3, 4, 5, 6]),
    p.incompatible?.length ? el('p', { class: 'muted', text: 'Not run (the problem lacks what they need): ' + p.incompatible.map((x) => `${x.entrant} (needs ${x.missing})`).join(', ') }) : null,
    el('div', { class: 'grid2' }, charts));
}

function fightSection(fights) {
  if (!fights || !fights.entrants.length) return null;
  const rows = fights.entrants.map((a, i) => [a, ...fights.win_rate[i].map((v, j) => {
    const cell = el('span', { title: v === null ? '' : `${a} beats ${fights.entrants[j]} in ${Math.round(100 * v)} % of run pairs`,
      text: v === null ? '–' : `${Math.round(100 * v)} %` });
    return cell;
  })]);
  const t = table(['row beats column', ...fights.entrants], rows, fights.entrants.map((_, i) => i + 1));
  t.classList.add('fight');
  t.querySelectorAll('tbody tr').forEach((tr, i) => tr.querySelectorAll('td').forEach((td, j) => {
    if (j > 0) td.style.background = heat(fights.win_rate[i][j - 1]);
  }));
  return section('fights', 'Fight matrix',
    el('p', { class: 'muted', text: 'Row’s win rate against column over the problems both ran (a run pair is won by the lower final error; ties count half).' }), t);
}

export function benchPage(d, timing) {
  const report = d.report;
  const header = el('header', {}, el('h1', { text: 'Optimizer × problem matrix' }),
    el('p', { text: `budget ${report.budget} · ${report.seeds} seeds for stochastic entrants · ${report.problems.length} problems` }));
  const sections = [glance(report), ...report.problems.map(problemSection), fightSection(report.fights)];
  if (timing?.wall_seconds !== undefined) sections.push(section('timing', 'Timings', table(['', ''], [['whole bench (wall)', seconds(timing.wall_seconds)], ['threads', timing.threads]], [1])));
  const present = sections.filter(Boolean);
  const nav = el('nav', {}, present.map((s) => el('a', { href: '#' + s.id, text: s.querySelector('h2').textContent })));
  document.body.append(header, nav, el('main', {}, present));
}
