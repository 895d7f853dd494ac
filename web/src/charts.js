// Line charts with hover read-outs (Chart.js): convergence with quartile
// bands, ECDF staircases, a run's error per evaluation.
import { Chart, LineController, LineElement, PointElement, LinearScale, LogarithmicScale, Tooltip, Legend, Filler, Title }
  from 'chart.js';
import { el, fmt } from './util.js';

Chart.register(LineController, LineElement, PointElement, LinearScale, LogarithmicScale, Tooltip, Legend, Filler, Title);

/// Log axes label their decades only (1e-4, not 1.000e-4 and its neighbours).
function logTick(value) {
  const exponent = Math.log10(value);
  if (Math.abs(exponent - Math.round(exponent)) > 1e-9) return '';
  return Math.abs(exponent) < 4 ? String(Number(value.toPrecision(1))) : `1e${Math.round(exponent)}`;
}

const PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2', '#17becf', '#7f7f7f', '#bcbd22'];

/// `chart`: { title, x_label, y_label, log_x, log_y, y_min, y_max, series: [{ label, points: [[x, y]], band: [[lo, hi]], steps }] }.
export function lineChart(chart) {
  const canvas = el('canvas');
  const box = el('div', { class: 'chart' }, canvas);
  const datasets = [];
  chart.series.forEach((series, i) => {
    const color = PALETTE[i % PALETTE.length];
    const points = series.points.map(([x, y]) => ({ x, y }));
    if (series.band && series.band.length) {
      datasets.push({ label: `${series.label} q1`, data: series.points.map(([x], k) => ({ x, y: series.band[k][0] })),
        borderWidth: 0, pointRadius: 0, fill: false, band: true });
      datasets.push({ label: `${series.label} q3`, data: series.points.map(([x], k) => ({ x, y: series.band[k][1] })),
        borderWidth: 0, pointRadius: 0, fill: '-1', backgroundColor: color + '33', band: true });
    }
    datasets.push({ label: series.label, data: points, borderColor: color, backgroundColor: color, borderWidth: 2,
      pointRadius: 0, pointHitRadius: 6, stepped: series.steps ? 'after' : false, fill: false });
  });
  const scale = (log, title, min, max) => ({ type: log ? 'logarithmic' : 'linear', title: { display: true, text: title },
    min: min ?? undefined, max: max ?? undefined, ticks: { callback: (v) => (log ? logTick(v) : fmt(v)) } });
  const instance = new Chart(canvas, {
    type: 'line',
    data: { datasets },
    options: {
      animation: false, parsing: true, responsive: true, maintainAspectRatio: false,
      interaction: { mode: 'nearest', axis: 'x', intersect: false },
      scales: { x: scale(chart.log_x, chart.x_label, chart.x_min, chart.x_max),
        y: scale(chart.log_y, chart.y_label, chart.log_y ? undefined : chart.y_min, chart.log_y ? undefined : chart.y_max) },
      plugins: {
        title: { display: !!chart.title, text: chart.title },
        legend: { labels: { filter: (item, data) => !data.datasets[item.datasetIndex].band } },
        tooltip: { callbacks: { label: (c) => `${c.dataset.label}: ${fmt(c.parsed.y)} at ${fmt(c.parsed.x)}` } },
      },
    },
  });
  return { element: box, chart: instance };
}
