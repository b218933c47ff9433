//! Expansion (paper §3): from the start shapes, repeatedly take the
//! non-terminal shapes with the lowest group id, choose one of the rules
//! matching their tag at random (seeded), apply it to all of them and
//! replace them by what it makes, until only terminals remain or a budget
//! stops it.
//!
//! Everything is recorded: every shape ever made ([`Record`], with the
//! step that made it and the step that consumed it) and every step
//! ([`StepRecord`]: rule, parameters used, input and output shapes), so the
//! browser can show any step without recomputing, and a step can be
//! re-expanded or edited ([`Expansion::reexpand`]): the steps that depend on
//! it are undone (their shapes removed, the shapes they consumed restored)
//! and the expansion carries on from there, redoing only that subtree.
//!
//! Ids: group ids are handed out incrementally from the largest ever used;
//! shape ids count from 0 within each new group, in the order the operator
//! makes the shapes (for a split: by band along the orientation, then
//! across), which is what `regroup(k)` (`s mod k`) reads.
//!
//! Work is bounded per [`Expansion::work`] call: one step's input shapes
//! are processed a few at a time, so a job can yield between them.
use super::ast::{CurveDef, Grammar, Op, Rule};
use super::ops::{self, Wobble};
use super::{Ink, Shape};
use crate::core::error::{Error, Result};
use crate::core::rng::Rng;
use crate::tangle::geom::polygon::Polygon;
use glam::DVec2;
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

/// Expansion settings (the request's; defaults in [`super::api`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    pub seed: u64,
    /// Stop after this many steps.
    pub max_steps: usize,
    /// Stop before the live shapes would exceed this.
    pub max_shapes: usize,
    /// Polyline sampling of cut curves, drawing units (the paper: 2).
    pub resolution: f64,
    /// Hand-drawn wobble amplitude (0: none) and wavelength, drawing units.
    pub wobble: f64,
    pub wavelength: f64,
}

/// One shape ever made, with its life span in step ids.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    pub shape: Shape,
    /// Id of the step that made it (`None`: a start shape).
    pub born: Option<u32>,
    /// Id of the step that consumed it (`None`: in the tangle).
    pub died: Option<u32>,
}

/// One expansion step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepRecord {
    /// A unique id (positions change when steps are undone; ids do not).
    pub id: u32,
    /// Index of the rule in the grammar.
    pub rule: usize,
    /// The operator with the parameters used (an edit may differ from the rule's).
    pub op: Op,
    /// The group it expanded.
    pub group: u32,
    /// Indices into [`Expansion::records`].
    pub inputs: Vec<u32>,
    pub outputs: Vec<u32>,
    /// The work it took (see [`MAX_WORK`]).
    pub work: u64,
}

/// Why an expansion ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Ending {
    /// Only terminals remain.
    Complete,
    /// A budget stopped it; the message says which and what to do.
    Stopped(String),
}

/// What [`Expansion::work`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum Progress {
    /// Part of a step; call again.
    Working,
    /// A step completed (its position in [`Expansion::steps`]).
    Stepped(usize),
    /// Nothing is left to do.
    Ended,
}

/// A rule resolved for running: curves and motifs as geometry.
#[derive(Debug, Clone)]
struct Resolved {
    curves: HashMap<String, CurveDef>,
    motifs: HashMap<String, Polygon>,
}

/// A step under way.
#[derive(Debug, Clone)]
struct Pending {
    rule: usize,
    op: Op,
    group: u32,
    inputs: Vec<u32>,
    next: usize,
    /// Output slots: shapes made so far, each with the input it came from.
    slots: Vec<Vec<(Polygon, u32)>>,
    /// Work done on it so far.
    work: u64,
    /// First group id of the slots.
    first_group: u32,
}

/// Input shapes processed per [`Expansion::work`] call (a split or an
/// outline of one shape is well under a millisecond for typical sizes).
const SHAPES_PER_WORK: usize = 8;

/// Work (see [`MAX_WORK`]) after which an [`Expansion::work`] call takes
/// no further shape: about 40 ms natively, so a step of a few costly
/// shapes (placements into large regions) is still cut into short slices.
const WORK_PER_CALL: u64 = 2_000_000;

/// The work budget of a tangle: the operators' cost (points read and
/// written, booleans weighted n·log n, a fixed cost per application) of
/// the steps it holds, counted, not timed, so native and wasm stop at the
/// same place. The shipped examples use at most 71 million (the village);
/// a grammar that recurses through an outline, a placement or a fine split
/// forever reaches it in about 3 s natively and 6 s in wasm (at 150
/// million an outline cycle took 4.2 s and 9 s: issue 34 asks ~5 s).
pub const MAX_WORK: u64 = 100_000_000;

/// The work budget of everything a document's edits redo, undone steps
/// included (a document of 1,000 edits took 98 s to replay in wasm).
pub const MAX_REPLAY_WORK: u64 = 8 * MAX_WORK;

/// The most points all shapes ever made may hold together (the live ones
/// and the history the step slider shows): about 64 MB of points.
pub const MAX_POINTS: usize = 4_000_000;

/// The most shapes ever made (live and history).
pub const MAX_HISTORY: usize = 250_000;

/// How much a point costs an operator relative to a boolean sweep: an
/// outline's inset (offset curves, then a boolean) about three sweeps; a
/// streamline split about six (its field's mean value sums over the
/// boundary samples: the cost oracle of the `tangle_grammar` fuzz target
/// found a streamline step of the letters at ~120 ns a unit natively,
/// where the budget assumes ~20).
fn weight(op: &Op) -> u64 {
    match op {
        Op::Outline { .. } => 3,
        Op::Streamline { .. } => 6,
        _ => 1,
    }
}

/// Work of a boolean or offset over `n` points: sweeps cost n·log n.
fn sweep_work(n: usize) -> u64 {
    let n = n as u64;
    n * (64 - n.leading_zeros() as u64).max(1)
}

/// Work an operator costs whatever the points: the overhead of one
/// application (booleans, offsets), and a placement's raster passes
/// (about `CELLS_PER_SPACING` cells per sample spacing along the longer
/// side, at most `MAX_RASTER`, swept by each Lloyd round).
fn fixed_work(op: &Op, poly: &Polygon) -> u64 {
    const PER_APPLICATION: u64 = 2_000;
    match op {
        Op::Place { size, distance, .. } => {
            let (lo, hi) = poly.bbox();
            let extent = (hi - lo).max_element().max(1.0);
            let spacing = (size + distance).max(super::ast::MIN_LENGTH);
            let side = (8.0 * extent / spacing).clamp(1.0, super::place::MAX_RASTER as f64) as u64;
            // Darts: thrown until MAX_MISSES fail in a row, each tested
            // against the copies placed so far.
            const DARTS: u64 = 60_000;
            PER_APPLICATION + DARTS + side * side * (super::place::LLOYD_ITERATIONS as u64 + 2)
        }
        _ => PER_APPLICATION,
    }
}

/// What applying `op` to `poly` may cost, before it runs: (shapes made,
/// points made, work), upper estimates from the shape's size and the
/// operator's parameters (a split's cut count, a stippling's grid).
fn estimate(op: &Op, poly: &Polygon, settings: &Settings) -> (usize, usize, u64) {
    let v = poly.vertices();
    let (lo, hi) = poly.bbox();
    let diag = (hi - lo).length().max(1.0);
    let step = settings.resolution.max(0.25);
    let perimeter: f64 = poly
        .rings
        .iter()
        .map(|r| {
            r.iter()
                .zip(r.iter().cycle().skip(1))
                .map(|(a, b)| a.distance(*b))
                .sum::<f64>()
        })
        .sum();
    let resampled = if settings.wobble > 0.0 {
        (perimeter / step) as usize + v
    } else {
        v
    };
    match op {
        Op::Ungroup | Op::Regroup { .. } | Op::Fill { .. } | Op::Invert => {
            (1, 0, v as u64 + fixed_work(op, poly))
        }
        Op::Split { offsets, dual, .. } => {
            let o = offsets
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min)
                .max(super::ast::MIN_LENGTH);
            let cuts = ((diag / o) as usize + 1).min(super::ops::MAX_CUTS);
            let per_cut = (diag / step) as usize + 8;
            let lines = if *dual { 2 * cuts } else { cuts };
            let pieces = if *dual {
                (cuts + 1) * (cuts + 1)
            } else {
                cuts + 1
            };
            // Every cut line's points end up on the pieces on both sides.
            let points = resampled + 2 * lines * per_cut + 4 * pieces;
            (
                pieces,
                points,
                sweep_work(resampled + points) + fixed_work(op, poly),
            )
        }
        Op::Outline { .. } => {
            let points = 3 * resampled;
            (
                2,
                points,
                weight(op) * sweep_work(resampled + points) + fixed_work(op, poly),
            )
        }
        Op::Streamline { offset, .. } => {
            let lines = ((diag / offset.max(super::ast::MIN_LENGTH)) as usize + 1)
                .min(super::ops::MAX_CUTS);
            let points = resampled + 2 * lines * ((diag / step) as usize + 8);
            (
                lines + 1,
                points,
                weight(op) * sweep_work(resampled + points) + fixed_work(op, poly),
            )
        }
        Op::Place { .. } => {
            let n = super::place::MAX_PLACEMENTS;
            let points = resampled + n * 64;
            (
                n + 1,
                points,
                sweep_work(resampled + points) + fixed_work(op, poly),
            )
        }
        Op::Stipple { spacing, .. } => {
            let s = spacing.max(super::ast::MIN_LENGTH);
            let cells = ((hi - lo).x / s + 1.0) * ((hi - lo).y / s + 1.0);
            let marks = (cells as usize).min(super::ops::MAX_MARKS);
            let points = v + marks * 32;
            (
                marks + 1,
                points,
                (v as f64 + cells.min(1e15)) as u64 + points as u64 + fixed_work(op, poly),
            )
        }
    }
}

/// The state of one tangle's expansion.
#[derive(Debug, Clone)]
pub struct Expansion {
    grammar: Grammar,
    resolved: Resolved,
    pub settings: Settings,
    /// The tag table: `Shape::tag` indexes it.
    pub tags: Vec<String>,
    /// Rules by tag index.
    rules_by_tag: Vec<Vec<usize>>,
    pub records: Vec<Record>,
    pub steps: Vec<StepRecord>,
    /// Live non-terminal shapes by group.
    queue: BTreeMap<u32, Vec<u32>>,
    next_group: u32,
    next_step: u32,
    live: usize,
    pending: Option<Pending>,
    pub ending: Option<Ending>,
    /// Per group: the rule and operator to use instead of a random choice.
    forced: HashMap<u32, (usize, Op)>,
    /// Per group: extra seed salt (a re-expansion draws anew).
    salt: HashMap<u32, u64>,
    /// Records removed by undone steps (never shown again).
    removed: Vec<bool>,
    /// Work of the steps held (see [`MAX_WORK`]), work ever done (see
    /// [`MAX_REPLAY_WORK`]), and points held by all records.
    work_live: u64,
    work_total: u64,
    points: usize,
}

fn hash(parts: &[u64]) -> u64 {
    let mut r = Rng::new(0x7a6e_6c65);
    let mut h = 0u64;
    for &p in parts {
        h = Rng::new(h ^ p ^ r.next_u64()).next_u64();
    }
    h
}

impl Expansion {
    /// Set up an expansion of `start` shapes (polygon, tag) under `grammar`.
    /// Each start tag forms one group, in order of first appearance.
    pub fn new(
        grammar: Grammar,
        start: Vec<(Polygon, String)>,
        motifs: HashMap<String, Polygon>,
        settings: Settings,
    ) -> Result<Expansion> {
        let curves = grammar
            .defs
            .iter()
            .map(|d| (d.name.clone(), d.curve.clone()))
            .collect();
        let mut x = Expansion {
            resolved: Resolved { curves, motifs },
            settings,
            tags: vec![],
            rules_by_tag: vec![],
            records: vec![],
            steps: vec![],
            queue: BTreeMap::new(),
            next_group: 0,
            next_step: 0,
            live: 0,
            pending: None,
            ending: None,
            forced: HashMap::new(),
            salt: HashMap::new(),
            removed: vec![],
            work_live: 0,
            work_total: 0,
            points: 0,
            grammar,
        };
        for i in 0..x.grammar.rules.len() {
            let t = x.tag(&x.grammar.rules[i].tag.clone());
            x.rules_by_tag[t as usize].push(i);
        }
        let mut groups: Vec<(String, u32, u32)> = vec![];
        for (poly, tag) in start {
            let (group, id) = match groups.iter_mut().find(|g| g.0 == tag) {
                Some(g) => {
                    g.2 += 1;
                    (g.1, g.2 - 1)
                }
                None => {
                    let g = x.next_group;
                    x.next_group += 1;
                    groups.push((tag.clone(), g, 1));
                    (g, 0)
                }
            };
            let t = x.tag(&tag);
            // Sampled finely only where it will wobble.
            let poly = if x.settings.wobble > 0.0 {
                poly.resampled(x.settings.resolution)
            } else {
                poly
            };
            x.add(
                Shape {
                    tag: t,
                    group,
                    id,
                    poly: Arc::new(poly),
                    dir: DVec2::Y,
                    ink: Ink::default(),
                },
                None,
            );
        }
        if x.live > x.settings.max_shapes {
            return Err(Error::limit(format!(
                "{} start shapes exceed the shape budget of {}",
                x.live, x.settings.max_shapes
            )));
        }
        Ok(x)
    }

    /// The grammar being expanded.
    pub fn grammar(&self) -> &Grammar {
        &self.grammar
    }

    fn tag(&mut self, name: &str) -> u32 {
        if let Some(i) = self.tags.iter().position(|t| t == name) {
            return i as u32;
        }
        self.tags.push(name.to_string());
        self.rules_by_tag.push(vec![]);
        (self.tags.len() - 1) as u32
    }

    fn terminal(&self, tag: u32) -> bool {
        self.rules_by_tag[tag as usize].is_empty()
    }

    fn add(&mut self, shape: Shape, born: Option<u32>) -> u32 {
        let i = self.records.len() as u32;
        self.points += shape.poly.vertices();
        if !self.terminal(shape.tag) {
            self.queue.entry(shape.group).or_default().push(i);
        }
        self.records.push(Record {
            shape,
            born,
            died: None,
        });
        self.removed.push(false);
        self.live += 1;
        i
    }

    /// Live shapes now.
    pub fn live(&self) -> usize {
        self.live
    }

    /// Whether record `i` was removed by an undone step.
    pub fn is_removed(&self, i: usize) -> bool {
        self.removed[i]
    }

    /// Run to the end (tests, the CLI).
    pub fn run(&mut self) -> Result<()> {
        while self.work()? != Progress::Ended {}
        Ok(())
    }

    /// Work of the steps held, in the units of [`MAX_WORK`].
    pub fn work_held(&self) -> u64 {
        self.work_live
    }

    /// Do a bounded part of the expansion.
    pub fn work(&mut self) -> Result<Progress> {
        if self.ending.is_some() {
            return Ok(Progress::Ended);
        }
        let Some(mut p) = self.pending.take() else {
            self.begin_step()?;
            return Ok(if self.ending.is_some() {
                Progress::Ended
            } else {
                Progress::Working
            });
        };
        // Shapes until SHAPES_PER_WORK or WORK_PER_CALL (counted, so the
        // slices fall alike natively and in wasm), at least one.
        let (first, mut end, mut call_work) = (p.next, p.next, 0u64);
        while end < p.inputs.len()
            && end < first + SHAPES_PER_WORK
            && (end == first || call_work < WORK_PER_CALL)
        {
            let i = p.inputs[end];
            end += 1;
            let input = &self.records[i as usize].shape.poly;
            let (shapes, points, work) = estimate(&p.op, input, &self.settings);
            let made_so_far: usize = p.slots.iter().map(Vec::len).sum();
            let points_so_far: usize = p.slots.iter().flatten().map(|(q, _)| q.vertices()).sum();
            let over = if self.work_live + p.work + work > MAX_WORK {
                Some(format!("the work budget of {MAX_WORK} point operations"))
            } else if self.work_total.saturating_add(work) > MAX_REPLAY_WORK {
                Some(format!(
                    "the replay budget of {MAX_REPLAY_WORK} point operations (this \
                     document's edits redo too much work)"
                ))
            } else if self.points + points_so_far + points > MAX_POINTS {
                Some(format!("the point budget of {MAX_POINTS} points"))
            } else if self.records.len() + made_so_far + shapes > MAX_HISTORY {
                Some(format!("the history budget of {MAX_HISTORY} shapes"))
            } else {
                None
            };
            if let Some(budget) = over {
                return Ok(self.stop_before(p, &budget));
            }
            let (in_points, fixed) = (input.vertices(), fixed_work(&p.op, input));
            let made = self.apply(&p, i)?;
            let out_points: usize = made.iter().flatten().map(Polygon::vertices).sum();
            let done = weight(&p.op) * sweep_work(in_points + out_points) + fixed;
            call_work += done;
            p.work += done;
            self.work_total = self.work_total.saturating_add(done);
            for (slot, polys) in made.into_iter().enumerate() {
                p.slots[slot].extend(polys.into_iter().map(|q| (q, i)));
            }
        }
        p.next = end;
        if p.next < p.inputs.len() {
            self.pending = Some(p);
            return Ok(Progress::Working);
        }
        self.finish_step(p)
    }

    /// Pick the lowest group, choose its rule, allocate its groups.
    fn begin_step(&mut self) -> Result<()> {
        let Some((&group, _)) = self.queue.iter().next() else {
            self.ending = Some(Ending::Complete);
            return Ok(());
        };
        if self.steps.len() >= self.settings.max_steps {
            self.ending = Some(Ending::Stopped(format!(
                "stopped after {} steps (the step budget) with {} shapes; shapes tagged '{}' \
                 still have rules to run: raise the step budget, or check for a rule that \
                 recurses without end",
                self.steps.len(),
                self.live,
                self.tags[self.records[self.queue[&group][0] as usize].shape.tag as usize]
            )));
            return Ok(());
        }
        let inputs = self.queue.remove(&group).unwrap_or_default();
        let tag = self.records[inputs[0] as usize].shape.tag;
        let (rule, op) = match self.forced.remove(&group) {
            Some(f) => f,
            None => {
                let cands = &self.rules_by_tag[tag as usize];
                let salt = self.salt.get(&group).copied().unwrap_or(0);
                let mut rng = Rng::new(hash(&[self.settings.seed, group as u64, salt]));
                let r = cands[rng.below(cands.len())];
                (r, self.grammar.rules[r].op.clone())
            }
        };
        let slots = match &op {
            Op::Ungroup => inputs.len(),
            Op::Regroup { k } => (*k as usize).min(inputs.len()).max(1),
            Op::Outline { .. } | Op::Place { .. } => 2,
            Op::Fill { .. } | Op::Invert => 1,
            Op::Stipple { .. } => 2,
            Op::Split { .. } | Op::Streamline { .. } => 1,
        };
        let first_group = self.next_group;
        self.next_group = self
            .next_group
            .checked_add(slots as u32)
            .ok_or_else(|| Error::limit("the tangle ran out of group ids"))?;
        self.pending = Some(Pending {
            rule,
            op,
            group,
            inputs,
            next: 0,
            slots: vec![vec![]; slots],
            work: 0,
            first_group,
        });
        Ok(())
    }

    fn wobble(&self, group: u32) -> Wobble {
        Wobble {
            amplitude: self.settings.wobble,
            wavelength: self.settings.wavelength,
            seed: hash(&[self.settings.seed, group as u64, 0x0b]),
        }
    }

    /// The operator on one input shape: its output slots.
    fn apply(&self, p: &Pending, i: u32) -> Result<Vec<Vec<Polygon>>> {
        let s = &self.records[i as usize].shape;
        let poly: &Polygon = &s.poly;
        let step = self.settings.resolution;
        let wob = self.wobble(p.first_group);
        let mut rng = Rng::new(hash(&[
            self.settings.seed,
            s.group as u64,
            s.id as u64,
            0x5a,
        ]));
        Ok(match &p.op {
            // Grouping and decoration keep the geometry (handled in finish_step).
            Op::Ungroup | Op::Regroup { .. } | Op::Fill { .. } | Op::Invert => {
                vec![vec![poly.clone()]]
            }
            Op::Split {
                curve,
                offsets,
                dual,
            } => {
                let c = self
                    .resolved
                    .curves
                    .get(curve)
                    .cloned()
                    .unwrap_or(CurveDef::Line);
                vec![ops::regular_split(
                    poly, s.dir, &c, offsets, *dual, step, &wob,
                )]
            }
            Op::Outline { distance } => ops::outline(poly, *distance, step, &wob).into(),
            Op::Streamline { kind, offset } => {
                let cuts: Vec<Vec<DVec2>> =
                    super::streamline::streamline_cuts(poly, *kind, *offset)
                        .into_iter()
                        .map(|line| line.into_iter().map(|p| wob.at(p)).collect())
                        .collect();
                vec![poly.slice(&cuts)]
            }
            Op::Place {
                size,
                distance,
                shape,
            } => {
                let motif = self.resolved.motifs.get(shape).ok_or_else(|| {
                    Error::input(format!("place: there is no shape called '{shape}'"))
                })?;
                let p = super::place::place(poly, motif, *size, *distance, &mut rng);
                vec![p.placed, p.remainder]
            }
            Op::Stipple {
                kind,
                spacing,
                size,
            } => vec![
                vec![poly.clone()],
                ops::stipple(poly, *kind, *spacing, *size, &mut rng),
            ],
        })
    }

    /// Stop before step `p` would pass `budget`: its inputs stay as they
    /// were (the step is not applied) and the ending names the rule, its
    /// line and the budget.
    fn stop_before(&mut self, p: Pending, budget: &str) -> Progress {
        let rule = &self.grammar.rules[p.rule];
        self.ending = Some(Ending::Stopped(format!(
            "stopped at step {}: rule {} (line {}, '{}') would pass {}; the tangle keeps \
             its {} steps so far. Use a coarser rule (larger distances or offsets, a \
             smaller start shape), or check for a rule that recurses without end",
            self.steps.len() + 1,
            p.rule + 1,
            rule.line,
            rule.tag,
            budget,
            self.steps.len()
        )));
        self.queue.insert(p.group, p.inputs);
        self.pending = None;
        Progress::Ended
    }

    /// Label the step's shapes, replace its inputs, record it.
    fn finish_step(&mut self, p: Pending) -> Result<Progress> {
        let made: usize = p.slots.iter().map(Vec::len).sum();
        if self.live - p.inputs.len() + made > self.settings.max_shapes {
            self.queue.insert(p.group, p.inputs.clone());
            self.ending = Some(Ending::Stopped(format!(
                "stopped at step {}: rule {} (line {}) would make the tangle {} shapes, over \
                 the shape budget of {}; raise the shape budget, or check for a rule that \
                 recurses without end",
                self.steps.len() + 1,
                p.rule + 1,
                self.grammar.rules[p.rule].line,
                self.live - p.inputs.len() + made,
                self.settings.max_shapes
            )));
            return Ok(Progress::Ended);
        }
        let id = self.next_step;
        self.next_step += 1;
        let rule: &Rule = &self.grammar.rules[p.rule];
        let outputs_tags: Vec<String> = rule.outputs.clone();
        let tag_of =
            |slot: usize| outputs_tags[slot.min(outputs_tags.len().saturating_sub(1))].clone();
        let mut outputs = vec![];
        for &i in &p.inputs {
            self.records[i as usize].died = Some(id);
            self.live -= 1;
        }
        let mut counters = vec![0u32; p.slots.len()];
        for (slot, shapes) in p.slots.into_iter().enumerate() {
            for (k, (poly, from)) in shapes.into_iter().enumerate() {
                let parent = self.records[from as usize].shape.clone();
                // Which group and which output tag this shape gets.
                let (g_slot, t_slot) = match &p.op {
                    Op::Ungroup => (k, 0),
                    Op::Regroup { k: m } => ((parent.id % (*m).max(1)) as usize, 0),
                    _ => (slot, slot),
                };
                let group = p.first_group + g_slot as u32;
                let id_in_group = counters.get(g_slot).copied().unwrap_or(0);
                if let Some(c) = counters.get_mut(g_slot) {
                    *c += 1;
                }
                let mut ink = if slot == 0 {
                    parent.ink
                } else {
                    Ink::default()
                };
                match &p.op {
                    Op::Fill { tone } => ink.fill = *tone as f32,
                    Op::Invert => {
                        ink.fill = 1.0;
                        ink.white_lines = true;
                    }
                    Op::Stipple { .. } if slot == 1 => ink.mark = true,
                    _ => {}
                }
                let same = matches!(
                    p.op,
                    Op::Ungroup | Op::Regroup { .. } | Op::Fill { .. } | Op::Invert
                ) || (matches!(p.op, Op::Stipple { .. }) && slot == 0);
                let tag = self.tag(&tag_of(t_slot));
                let shape = Shape {
                    tag,
                    group,
                    id: id_in_group,
                    poly: if same {
                        parent.poly.clone()
                    } else {
                        Arc::new(poly)
                    },
                    dir: parent.dir,
                    ink,
                };
                outputs.push(self.add(shape, Some(id)));
            }
        }
        // Regroup's counters are per new group; its group count is k.
        self.work_live += p.work;
        self.steps.push(StepRecord {
            id,
            rule: p.rule,
            op: p.op,
            group: p.group,
            inputs: p.inputs,
            outputs,
            work: p.work,
        });
        Ok(Progress::Stepped(self.steps.len() - 1))
    }

    /// The position of the step that made the group of record `shape`
    /// (`None`: a start shape); from a step, the step that made the
    /// group of its inputs (the paper's repeated click).
    pub fn step_of(&self, shape: usize) -> Option<usize> {
        let born = self.records.get(shape)?.born?;
        self.steps.iter().position(|s| s.id == born)
    }

    /// The step before `step` in the paper's history walk: the one that
    /// made the shapes `step` matched.
    pub fn parent_step(&self, step: usize) -> Option<usize> {
        let first = *self.steps.get(step)?.inputs.first()?;
        self.step_of(first as usize)
    }

    /// Positions of the steps that depend on `step` (itself included):
    /// whose inputs contain a shape added by it or by another dependent.
    pub fn dependents(&self, step: usize) -> Vec<usize> {
        let mut made: std::collections::HashSet<u32> = std::collections::HashSet::new();
        let mut out = vec![];
        for (k, s) in self.steps.iter().enumerate().skip(step) {
            if k == step || s.inputs.iter().any(|i| made.contains(i)) {
                out.push(k);
                made.extend(s.outputs.iter().copied());
            }
        }
        out
    }

    /// Re-expand step `step` (paper §6): undo it and every step that
    /// depends on it, then expand again from there. With `op`, the step's
    /// shapes are redone with that operator (edited parameters); without,
    /// a new random rule is drawn for them.
    pub fn reexpand(&mut self, step: usize, op: Option<Op>) -> Result<()> {
        let Some(target) = self.steps.get(step).cloned() else {
            return Err(Error::input(format!(
                "there is no step {} (the tangle has {} steps)",
                step + 1,
                self.steps.len()
            ))
            .at("step"));
        };
        // Finish or drop a step under way: its inputs go back to the queue.
        if let Some(p) = self.pending.take() {
            self.queue.insert(p.group, p.inputs);
        }
        let deps = self.dependents(step);
        for &k in deps.iter().rev() {
            let s = self.steps[k].clone();
            self.work_live -= s.work;
            for &o in &s.outputs {
                let o = o as usize;
                self.removed[o] = true;
                if self.records[o].died.is_none() {
                    self.live -= 1;
                }
                let sh = &self.records[o].shape;
                if let Some(q) = self.queue.get_mut(&sh.group) {
                    q.retain(|&x| x as usize != o);
                    if q.is_empty() {
                        self.queue.remove(&sh.group);
                    }
                }
            }
            for &i in &s.inputs {
                self.records[i as usize].died = None;
                self.live += 1;
            }
            self.queue.insert(s.group, s.inputs.clone());
        }
        let keep: std::collections::HashSet<usize> = deps.into_iter().collect();
        let mut k = 0;
        self.steps.retain(|_| {
            k += 1;
            !keep.contains(&(k - 1))
        });
        match op {
            Some(op) => {
                self.forced.insert(target.group, (target.rule, op));
            }
            None => *self.salt.entry(target.group).or_insert(0) += 1,
        }
        self.ending = None;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tangle::ast::Rule;

    fn rule(op: Op, tag: &str, outputs: &[&str]) -> Rule {
        Rule {
            op,
            tag: tag.into(),
            outputs: outputs.iter().map(|s| s.to_string()).collect(),
            line: 1,
            column: 1,
        }
    }

    fn settings() -> Settings {
        Settings {
            seed: 5,
            max_steps: 1000,
            max_shapes: 10_000,
            resolution: 2.0,
            wobble: 0.0,
            wavelength: 40.0,
        }
    }

    fn run(rules: Vec<Rule>, s: Settings) -> Expansion {
        let g = Grammar {
            rules,
            ..Default::default()
        };
        let start = vec![(
            Polygon::rect(DVec2::ZERO, DVec2::new(90.0, 90.0)),
            "a".to_string(),
        )];
        let mut x = Expansion::new(g, start, HashMap::new(), s).unwrap();
        x.run().unwrap();
        x
    }

    fn grid(n: f64) -> Op {
        Op::Split {
            curve: "line".into(),
            offsets: vec![90.0 / n],
            dual: true,
        }
    }

    fn finals(x: &Expansion) -> Vec<&Record> {
        x.records
            .iter()
            .enumerate()
            .filter(|(i, r)| r.died.is_none() && !x.is_removed(*i))
            .map(|(_, r)| r)
            .collect()
    }

    /// regroup(k) puts shape s in new group s mod k (paper §4.1); ids
    /// count from 0 in each new group; ungroup gives every shape a group.
    #[test]
    fn regroup_and_ungroup_assign_ids_as_the_paper_defines() {
        let x = run(
            vec![
                rule(grid(3.0), "a", &["q"]),
                rule(Op::Regroup { k: 2 }, "q", &["r"]),
            ],
            settings(),
        );
        assert_eq!(x.steps.len(), 2);
        let split = &x.steps[0];
        assert_eq!(split.outputs.len(), 9);
        let regroup = &x.steps[1];
        for (k, &o) in regroup.outputs.iter().enumerate() {
            let parent = &x.records[regroup.inputs[k] as usize].shape;
            let s = &x.records[o as usize].shape;
            assert_eq!(
                s.group,
                2 + parent.id % 2,
                "new groups start after the largest id"
            );
        }
        // Chessboard: in a 3×3 grid, even shape ids alternate.
        let g: Vec<u32> = regroup
            .outputs
            .iter()
            .map(|&o| x.records[o as usize].shape.group)
            .collect();
        assert_eq!(g, [2, 3, 2, 3, 2, 3, 2, 3, 2]);
        let ids: Vec<u32> = regroup
            .outputs
            .iter()
            .map(|&o| x.records[o as usize].shape.id)
            .collect();
        assert_eq!(ids, [0, 0, 1, 1, 2, 2, 3, 3, 4]);

        let x = run(
            vec![rule(grid(2.0), "a", &["q"]), rule(Op::Ungroup, "q", &["u"])],
            settings(),
        );
        let groups: Vec<u32> = finals(&x).iter().map(|r| r.shape.group).collect();
        assert_eq!(groups, [2, 3, 4, 5]);
        assert!(finals(&x).iter().all(|r| r.shape.id == 0));
    }

    /// Lowest group first; a tag with several rules picks one at random
    /// per group (seeded), so the same seed gives the same choices.
    #[test]
    fn groups_expand_lowest_first_with_a_seeded_rule_choice() {
        let rules = || {
            vec![
                rule(grid(3.0), "a", &["q"]),
                rule(Op::Ungroup, "q", &["u"]),
                rule(Op::Outline { distance: 3.0 }, "u", &["in", "ring"]),
                rule(
                    Op::Split {
                        curve: "line".into(),
                        offsets: vec![10.0],
                        dual: false,
                    },
                    "u",
                    &["slices"],
                ),
            ]
        };
        let x = run(rules(), settings());
        let groups: Vec<u32> = x.steps.iter().map(|s| s.group).collect();
        assert!(groups.windows(2).all(|w| w[0] < w[1]), "{groups:?}");
        let chosen: Vec<usize> = x.steps.iter().skip(2).map(|s| s.rule).collect();
        assert!(
            chosen.contains(&2) && chosen.contains(&3),
            "both rules drawn: {chosen:?}"
        );
        let again = run(rules(), settings());
        assert_eq!(again.steps, x.steps);
        let other = run(
            rules(),
            Settings {
                seed: 6,
                ..settings()
            },
        );
        assert_ne!(
            other.steps.iter().map(|s| s.rule).collect::<Vec<_>>(),
            x.steps.iter().map(|s| s.rule).collect::<Vec<_>>()
        );
    }

    /// The final shapes tile the start shape: area is conserved through
    /// splits and outlines, with wobble.
    #[test]
    fn splits_and_outlines_conserve_the_start_area() {
        let s = Settings {
            wobble: 1.5,
            ..settings()
        };
        let x = run(
            vec![
                rule(Op::Outline { distance: 8.0 }, "a", &["in", "ring"]),
                rule(grid(4.0), "in", &["q"]),
                rule(Op::Outline { distance: 3.0 }, "q", &["t", "t"]),
            ],
            s,
        );
        let area: f64 = finals(&x).iter().map(|r| r.shape.poly.area()).sum();
        assert!((area - 8100.0).abs() < 1.0, "{area}");
        assert!(finals(&x).len() > 10);
    }

    /// A step of a few costly shapes is still cut into short slices: eight
    /// large placements (each past `WORK_PER_CALL`) take eight `work`
    /// calls, not one (issue 34: every `step()` a short slice; they took
    /// 2.3 s in one wasm step).
    #[test]
    fn costly_shapes_are_worked_one_call_each() {
        let g = Grammar {
            rules: vec![rule(
                Op::Place {
                    size: 20.0,
                    distance: 3.0,
                    shape: "circle".into(),
                },
                "b",
                &["c", "d"],
            )],
            ..Default::default()
        };
        let start = (0..8)
            .map(|k| {
                let x0 = 210.0 * k as f64;
                let strip = Polygon::rect(DVec2::new(x0, 0.0), DVec2::new(x0 + 200.0, 3000.0));
                (strip, "b".to_string())
            })
            .collect();
        let mut motifs = HashMap::new();
        motifs.insert("circle".to_string(), Polygon::circle(DVec2::ZERO, 1.0, 32));
        let mut x = Expansion::new(g, start, motifs, settings()).unwrap();
        let mut calls = 0;
        loop {
            match x.work().unwrap() {
                Progress::Working => calls += 1,
                Progress::Stepped(_) => break,
                Progress::Ended => panic!("ended before the step"),
            }
        }
        // One call begins the step, then one per strip (the last one ends it).
        assert!(calls >= 8, "{calls} calls");
        assert!(x.steps[0].work > 8 * WORK_PER_CALL, "{}", x.steps[0].work);
    }

    /// The work a tangle holds is its steps' (undone steps give theirs
    /// back), so editing a step again and again never uses the work budget
    /// up; what the edits redo counts against the replay budget.
    #[test]
    fn held_work_is_the_steps_and_redone_work_is_counted_apart() {
        let rules = vec![
            rule(grid(18.0), "a", &["b"]),
            rule(Op::Outline { distance: 2.0 }, "b", &["c", "d"]),
        ];
        let mut x = run(rules, settings());
        let held = x.work_held();
        assert!(held > 0);
        assert_eq!(held, x.steps.iter().map(|s| s.work).sum::<u64>());
        let before = x.work_total;
        for _ in 0..3 {
            let op = x.steps[0].op.clone();
            x.reexpand(0, Some(op)).unwrap();
            x.run().unwrap();
            assert_eq!(x.work_held(), held, "the same steps hold the same work");
        }
        assert!(x.work_total >= before + 3 * held, "redone work is counted");
    }

    /// A rule that keeps making its own tag is stopped by the budgets
    /// with a message saying which and what to do.
    #[test]
    fn budgets_stop_a_runaway_grammar_with_a_clear_message() {
        let forever = || vec![rule(Op::Ungroup, "a", &["a"])];
        let x = run(
            forever(),
            Settings {
                max_steps: 50,
                ..settings()
            },
        );
        let Some(Ending::Stopped(m)) = &x.ending else {
            panic!("{:?}", x.ending)
        };
        assert!(m.contains("step budget") && m.contains("'a'"), "{m}");
        assert_eq!(x.steps.len(), 50);

        let split_forever = vec![rule(grid(18.0), "a", &["a"])];
        let x = run(
            split_forever,
            Settings {
                max_shapes: 100,
                ..settings()
            },
        );
        let Some(Ending::Stopped(m)) = &x.ending else {
            panic!("{:?}", x.ending)
        };
        assert!(
            m.contains("shape budget of 100") && m.contains("324 shapes"),
            "{m}"
        );
        assert_eq!(
            x.live(),
            1,
            "the step that would pass the budget is not applied"
        );
    }

    /// Re-expanding a step removes exactly its dependent steps' shapes and
    /// regrows them; editing its parameters changes only its subtree.
    #[test]
    fn reexpanding_an_edited_step_redoes_only_its_subtree() {
        let rules = vec![
            rule(grid(2.0), "a", &["q"]),
            rule(Op::Ungroup, "q", &["u"]),
            rule(Op::Outline { distance: 5.0 }, "u", &["t", "t2"]),
        ];
        let mut x = run(rules, settings());
        // Steps: split, ungroup, then 4 outlines (one per group).
        assert_eq!(x.steps.len(), 6);
        let before: Vec<(u32, Vec<DVec2>)> = finals(&x)
            .iter()
            .map(|r| (r.shape.group, r.shape.poly.rings[0].clone()))
            .collect();
        let target = 3; // the second outline
        let g = x.steps[target].group;
        assert_eq!(x.dependents(target), vec![target]);
        assert_eq!(x.dependents(0).len(), 6);
        x.reexpand(target, Some(Op::Outline { distance: 12.0 }))
            .unwrap();
        assert_eq!(x.steps.len(), 5);
        x.run().unwrap();
        assert_eq!(x.steps.len(), 6);
        let last = x.steps.last().unwrap();
        assert_eq!(last.group, g);
        assert_eq!(last.op, Op::Outline { distance: 12.0 });
        // Shapes of the other groups are untouched.
        let after: Vec<(u32, Vec<DVec2>)> = finals(&x)
            .iter()
            .map(|r| (r.shape.group, r.shape.poly.rings[0].clone()))
            .collect();
        let untouched = |v: &Vec<(u32, Vec<DVec2>)>| {
            v.iter()
                .filter(|(gr, _)| {
                    x.steps
                        .iter()
                        .find(|s| {
                            s.outputs
                                .iter()
                                .any(|&o| x.records[o as usize].shape.group == *gr)
                        })
                        .is_some_and(|s| s.group != g)
                })
                .cloned()
                .collect::<Vec<_>>()
        };
        let (a, b) = (untouched(&before), untouched(&after));
        assert_eq!(a.len(), 6, "three other outlines, two shapes each");
        assert_eq!(a, b);
        let area: f64 = finals(&x).iter().map(|r| r.shape.poly.area()).sum();
        assert!((area - 8100.0).abs() < 1e-3);
        // History walk: a shape → its step → the step that made its inputs.
        let shape = last.outputs[0] as usize;
        let s = x.step_of(shape).unwrap();
        assert_eq!(s, 5);
        assert_eq!(
            x.parent_step(s),
            Some(1),
            "the ungroup made the outline's input"
        );
        assert_eq!(x.parent_step(1), Some(0));
        assert_eq!(x.parent_step(0), None);
    }
}
