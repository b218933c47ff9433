// The long jobs of the documents, for the document controller (document.js):
// a fit, a reconstruction, a tangle's growth belongs to its tool's document,
// not to its panel. Leaving the panel does not stop it; the tool bar hears
// of it (the controller's `onJob`); the panel finds it again when it comes
// back (`ctx.job(name)`).
//
//   const jobs = new DocJobs(controller, onJob);
//   jobs.start(tool, name, {label, quietMs}, body) → DocJob (stops the last of that name)
//   jobs.of(toolId)                              → Map(name → DocJob), the last of each name
//   jobs.changed(job)                            a job moved on: the tool bar hears it
//   jobs.shown(toolId)                           its panel is mounted: its outcomes are seen

/**
 * A long job that belongs to a tool's document, not to its panel: leaving
 * the panel does not stop it; the tool bar shows its progress; the panel
 * finds it again when it comes back (`ctx.job(name)`) and shows where it is.
 * Its body reports (`report`), keeps the best answer so far (`best`), and
 * puts its outcome in the document with `commit`, whether the panel is
 * mounted or not.
 *
 *   status   'running' | 'done' | 'stopped' (the user's Stop: `best` is kept
 *            for the panel to offer) | 'cancelled' (`reason` says why) | 'failed' (`error`)
 *   progress {fraction, stage, figure}; points: [fraction, figure] for a plot
 *   data     the panel's own facts about the job (what it started from)
 */
export class DocJob {
  constructor(ctl, tool, name, { label = name, quietMs = 0 } = {}) {
    this.ctl = ctl;
    this.tool = tool;
    this.name = name;
    this.label = label;
    this.ctrl = new AbortController();
    this.signal = this.ctrl.signal;
    this.status = 'running';
    this.progress = { fraction: 0, stage: 'starting', figure: null };
    this.points = [];
    this.best = null;
    this.result = null;
    this.error = null;
    this.reason = '';
    this.data = {};
    this.seen = false; // its outcome was shown in its panel
    this.listeners = new Set();
    this.startedAt = performance.now();
    this.endedAt = null;
    // A job that may well end at once (a tangle's growth after an edit) reaches the tool
    // bar only once it has run `quietMs`; one that ends before stays quiet.
    this.quietUntil = this.startedAt + quietMs;
    this.announced = quietMs <= 0;
    if (!this.announced) setTimeout(() => { if (this.running) ctl.jobs.changed(this); }, quietMs);
  }

  get running() { return this.status === 'running'; }

  /** pool.run for this job: its module, its signal (Stop and cancel abort it). */
  run(kind, payload, opts = {}) {
    const signal = opts.signal ? AbortSignal.any([this.signal, opts.signal]) : this.signal;
    return this.ctl.pool.run(kind, payload, { module: this.tool.id, ...opts, signal });
  }

  /** pool.runSharded for this job. */
  runSharded(kind, payload, opts = {}) {
    return this.ctl.pool.runSharded(kind, payload, { ...opts, signal: this.signal });
  }

  /** Where the job is: `progress` (merged), a plot `point`, a new `best`. */
  report(progress, { point, best } = {}) {
    if (!this.running) return;
    this.progress = { ...this.progress, ...progress };
    if (point && point.every(Number.isFinite)) this.points.push(point);
    if (best !== undefined) this.best = best;
    this.changed();
  }

  /** Stop with `status` 'stopped' (the user's Stop, the best kept) or 'cancelled' with a reason. */
  stop(reason = '') {
    if (!this.running) return;
    this.stopAs = reason ? 'cancelled' : 'stopped';
    this.reason = reason;
    this.ctrl.abort();
  }

  /** The tool's document becomes `fn(present)` (null: unchanged), as one undoable step, mounted or not. */
  commit(fn) {
    return this.ctl.commitTo(this.tool.id, fn);
  }

  subscribe(fn) {
    this.listeners.add(fn);
    return () => this.listeners.delete(fn);
  }

  changed() {
    for (const fn of this.listeners) {
      try { fn(this); } catch (err) { console.error(err); }
    }
    this.ctl.jobs.changed(this);
  }

  /** Run `body(job)` to its end; the job's status says how it ended. */
  async start(body) {
    try {
      this.result = await body(this);
      this.status = this.signal.aborted ? this.stopAs || 'cancelled' : 'done';
    } catch (err) {
      if (this.signal.aborted || err?.kind === 'cancelled') {
        this.status = this.stopAs || 'cancelled';
        if (!this.reason && !this.stopAs) this.reason = 'its work was stopped';
      } else {
        this.status = 'failed';
        this.error = err;
      }
    }
    this.endedAt = performance.now();
    this.changed();
    return this;
  }
}


/** The jobs of every tool's document: the last of each name, per tool. */
export class DocJobs {
  constructor(ctl, onJob) {
    this.ctl = ctl;
    this.onJob = onJob; // onJob(job): a document's job started, moved on or ended (the tool bar shows it)
    this.byTool = new Map(); // tool id → Map(name → DocJob), the last of each name
  }

  /** The jobs of tool `id`'s document (name → DocJob). */
  of(id) {
    if (!this.byTool.has(id)) this.byTool.set(id, new Map());
    return this.byTool.get(id);
  }

  /** Start job `name` of `tool`'s document: `body(job)` runs on when the panel is left. Stops the last of that name. */
  start(tool, name, opts, body) {
    const jobs = this.of(tool.id);
    jobs.get(name)?.stop('a new one started');
    const job = new DocJob(this.ctl, tool, name, opts);
    jobs.set(name, job);
    job.promise = job.start(body);
    this.changed(job);
    return job;
  }

  /** A job moved on: the tool bar hears it; an outcome shown in its mounted panel is seen. */
  changed(job) {
    if (!job.running && this.ctl.current?.tool === job.tool) job.seen = true;
    if (!job.announced) {
      if (!job.running || performance.now() < job.quietUntil) return;
      job.announced = true;
    }
    this.onJob?.(job);
  }

  /** Tool `id`'s panel was mounted: its jobs' outcomes are shown from here on. */
  shown(id) {
    for (const job of this.of(id).values()) if (!job.running && !job.seen) { job.seen = true; if (job.announced) this.onJob?.(job); }
  }
}
