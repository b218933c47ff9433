// A small live line plot of a loss curve, drawn on a canvas: log-scaled y
// for a loss that is a plain positive number (Fit), linear for one that is
// already a logarithm and may be negative (Micro's log MSE), so the axis
// shows the numbers the status shows. The axis ends are also in the
// canvas's data-top and data-bottom.
// Forty lines do what a plotting library would here, with nothing to vendor.

export class LossPlot {
  /** `log`: a log-scaled y axis (losses > 0); `format(v)`: an axis label. */
  constructor(canvas, { log = true, format = (v) => v.toPrecision(3) } = {}) {
    this.canvas = canvas;
    this.points = [];
    this.log = log;
    this.format = format;
  }

  clear() {
    this.points = [];
    this.stage = null;
    this.draw();
  }

  /**
   * Shade the progress from 0 to `x` as a stage that has no loss of its own
   * to plot (Fit's global search compares spectra, not the loss), labelled.
   */
  shade(x, label) {
    if (!(x > 0) || (this.stage?.x === x && this.stage.label === label)) return;
    this.stage = { x: Math.min(1, x), label };
    this.draw();
  }

  /** Add the loss at `x` (e.g. the job's progress fraction). */
  push(x, loss) {
    if (!Number.isFinite(loss) || (this.log && loss <= 0)) return;
    this.points.push([x, loss]);
    this.draw();
  }

  draw() {
    const c = this.canvas;
    const dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth || 300, h = c.clientHeight || 140;
    c.width = w * dpr;
    c.height = h * dpr;
    const ctx = c.getContext('2d');
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, w, h);
    const pad = { l: 44, r: 8, t: 8, b: 18 };
    ctx.strokeStyle = '#363047';
    ctx.strokeRect(pad.l, pad.t, w - pad.l - pad.r, h - pad.t - pad.b);
    ctx.font = '11px system-ui, sans-serif';
    if (this.stage) {
      const sw = this.stage.x * (w - pad.l - pad.r);
      ctx.fillStyle = 'rgba(201, 162, 255, 0.14)';
      ctx.fillRect(pad.l, pad.t, sw, h - pad.t - pad.b);
      ctx.fillStyle = '#a49cb8';
      ctx.fillText(this.stage.label, pad.l + 4, h - pad.b - 4);
      c.dataset.stage = `${this.stage.label} ${this.stage.x.toFixed(3)}`;
    } else delete c.dataset.stage;
    ctx.fillStyle = '#a49cb8';
    if (this.points.length < 1) {
      delete c.dataset.top;
      delete c.dataset.bottom;
      if (!this.stage) ctx.fillText('loss appears here while fitting', pad.l + 8, h / 2);
      return;
    }
    const ys = this.points.map((p) => (this.log ? Math.log10(p[1]) : p[1]));
    let lo = Math.min(...ys), hi = Math.max(...ys);
    if (hi - lo < 1e-6) { lo -= 0.5; hi += 0.5; }
    const X = (x) => pad.l + x * (w - pad.l - pad.r);
    const Y = (y) => pad.t + (1 - (y - lo) / (hi - lo)) * (h - pad.t - pad.b);
    const [top, bottom] = [hi, lo].map((y) => this.format(this.log ? 10 ** y : y));
    c.dataset.top = top;
    c.dataset.bottom = bottom;
    ctx.fillText(top, 2, pad.t + 9);
    ctx.fillText(bottom, 2, h - pad.b);
    ctx.fillText('progress →', w - 70, h - 4);
    ctx.strokeStyle = '#c9a2ff';
    ctx.lineWidth = 1.6;
    ctx.beginPath();
    this.points.forEach(([x], i) => (i ? ctx.lineTo(X(x), Y(ys[i])) : ctx.moveTo(X(x), Y(ys[i]))));
    ctx.stroke();
  }
}
