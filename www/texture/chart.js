// Texture's bar chart: the requested and the retrieved scales side by side,
// redrawn when its box resizes; its label says the same in words.
import { SCALES, label } from './state.js';

const SHORT = ['Con', 'Rep', 'Gra', 'Ran', 'Rou', 'Den', 'Dir', 'Cpx', 'Coa', 'Reg', 'Ori', 'Uni'];

/** The chart of a mounted panel: {drawChart(doc), detach()}. */
export function createChart(ctx, { el, q }) {
  const chart = q('[data-testid=texture-chart]');
  const state = () => ctx.state();

  function drawChart(doc) {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(200, Math.round(chart.clientWidth || 320));
    const h = Math.max(90, Math.round(chart.clientHeight || 120));
    chart.width = Math.round(w * dpr);
    chart.height = Math.round(h * dpr);
    const g = chart.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    const css = getComputedStyle(el);
    const accent = css.getPropertyValue('--accent').trim() || '#c9a2ff';
    const accent2 = css.getPropertyValue('--accent-2').trim() || '#7fd1c7';
    const muted = css.getPropertyValue('--muted').trim() || '#a49cb8';
    const top = 4, bottom = h - 16, slot = w / 12;
    const y = (v) => bottom - ((v - 0) / 9) * (bottom - top);
    g.strokeStyle = '#363047';
    g.lineWidth = 1;
    for (const v of [1, 5, 9]) { g.beginPath(); g.moveTo(0, y(v) + 0.5); g.lineTo(w, y(v) + 0.5); g.stroke(); }
    const got = doc?.retrieved?.scales;
    g.font = '10px system-ui, sans-serif';
    g.textAlign = 'center';
    for (let i = 0; i < 12; i++) {
      const x0 = i * slot, bw = Math.max(2, slot * 0.34);
      if (doc) { g.fillStyle = accent; g.fillRect(x0 + slot * 0.14, y(doc.scales[i]), bw, bottom - y(doc.scales[i])); }
      if (got) { g.fillStyle = accent2; g.fillRect(x0 + slot * 0.52, y(got[i]), bw, bottom - y(got[i])); }
      g.fillStyle = muted;
      g.fillText(SHORT[i], x0 + slot / 2, h - 4);
    }
    const desc = SCALES.map((n, i) => `${label(n)} ${doc ? doc.scales[i] : '–'} vs ${got ? got[i] : '–'}`).join(', ');
    chart.setAttribute('aria-label', `requested vs retrieved scales: ${desc}`);
  }

  const ro = new ResizeObserver(() => drawChart(state()));
  ro.observe(chart);

  return { drawChart, detach: () => ro.disconnect() };
}
