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
    /// First group id of the slots.
    first_group: u32,
}

/// Input shapes processed per [`Expansion::work`] call (a split or an
/// outline of one shape is well under a millisecond for typical sizes).
const SHAPES_PER_WORK: usize = 8;

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
        let end = (p.next + SHAPES_PER_WORK).min(p.inputs.len());
        for k in p.next..end {
            let i = p.inputs[k];
            let made = self.apply(&p, i)?;
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
        self.steps.push(StepRecord {
            id,
            rule: p.rule,
            op: p.op,
            group: p.group,
            inputs: p.inputs,
            outputs,
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
