//! Output: when a frame is due, the master asks the workers for it in pieces of at most
//! `FRAME_PIECE` elements (consecutive bodies of one worker, in id order) and hands each
//! body to the sink as it arrives: neither the master nor the sink holds a large
//! model's frame at once (the file sink passes each body to its background writer,
//! whose queue is bounded).

use super::{ns, Master, TIME_EPS};
use crate::error::MasterError;
use crate::sink::Sink;
use crash_core::hash::StateHasher;
use crash_io::FrameBody;
use crash_link::{Command, LinkError, Reply, WorkerLink};
use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

/// A piece of a frame: consecutive bodies asked of one worker, or a split body from
/// its parts' shares.
pub(super) enum Piece {
    Worker(usize, Vec<u32>),
    Split(u32),
}

/// Most elements asked for in one frame request (a piece holds at least one body).
pub const FRAME_PIECE: usize = 100_000;

impl<L: WorkerLink> Master<'_, L> {
    /// Runs of consecutive body indices on one worker, each of at most `FRAME_PIECE`
    /// elements (or one body); the bodies of `apart` (split bodies whose frames come
    /// from their parts) each a piece of their own, with no worker.
    pub(super) fn frame_pieces(&self, apart: &BTreeMap<u32, FrameBody>) -> Vec<Piece> {
        let mut out: Vec<(Option<usize>, Vec<u32>, usize)> = Vec::new();
        for (i, inf) in self.info.iter().enumerate() {
            if apart.contains_key(&inf.id) {
                out.push((None, vec![inf.id], 0));
                continue;
            }
            let w = self.worker_of[i].unwrap_or(0);
            match out.last_mut() {
                Some((Some(lw), ids, n)) if *lw == w && *n + inf.elements <= FRAME_PIECE => {
                    ids.push(inf.id);
                    *n += inf.elements;
                }
                _ => out.push((Some(w), vec![inf.id], inf.elements)),
            }
        }
        out.into_iter()
            .map(|(w, ids, _)| match w {
                Some(w) => Piece::Worker(w, ids),
                None => Piece::Split(ids[0]),
            })
            .collect()
    }

    /// Stream the frame of every body now to the sink (None: only hash it); returns
    /// its state hash when `hashed`. Split bodies come from their parts' shares when
    /// they can (`frames_from_parts`; their pending contact pass has run), else from
    /// their home after an assembly. The workers build their pieces at the same time:
    /// each round asks every worker that holds no piece yet for its next one, and the
    /// pieces go to the sink in body order as they are complete, so the master holds
    /// at most one piece per worker.
    fn stream_frame(
        &mut self,
        mut sink: Option<&mut dyn Sink>,
        hashed: bool,
    ) -> Result<Option<u64>, MasterError> {
        let nw = self.links.len();
        let (step, time) = (self.clock.step, self.clock.time);
        if let Some(sink) = sink.as_mut() {
            sink.frame_begin(step, time).map_err(MasterError::sink)?;
        }
        let mut hash = StateHasher::default();
        let mut split = if self.frames_from_parts() {
            self.part_frames()?
        } else {
            BTreeMap::new()
        };
        let pieces = self.frame_pieces(&split);
        // each worker's pieces, in body order
        let mut queues: Vec<VecDeque<usize>> = vec![VecDeque::new(); nw];
        for (i, piece) in pieces.iter().enumerate() {
            if let Piece::Worker(w, _) = piece {
                queues[*w].push_back(i);
            }
        }
        let mut ready: BTreeMap<usize, (usize, Vec<FrameBody>)> = BTreeMap::new();
        for (i, piece) in pieces.iter().enumerate() {
            let (w, bodies) = match piece {
                Piece::Split(id) => {
                    let w = self.split_home(*id);
                    let Some(b) = split.remove(id) else {
                        return Err(self.implausible(w, &format!("no frame of body {id}")));
                    };
                    (w, vec![b])
                }
                Piece::Worker(w, _) => {
                    if !ready.contains_key(&i) {
                        self.frame_round(&pieces, &mut queues, &mut ready)?;
                    }
                    match ready.remove(&i) {
                        Some(got) => got,
                        None => return Err(self.bad_reply(*w, "Frame")),
                    }
                }
            };
            if let Err(what) = self.check_frame(&bodies) {
                return Err(self.implausible(w, &what));
            }
            // the state hash comes from the bodies as received, whatever the file format
            for mut b in bodies {
                if hashed {
                    hash.add(b.id, &b.x, &b.v, &b.w);
                }
                b.placement = self.placement_of(b.id);
                b.parts = self.split_cells(b.id);
                if self.is_kinematic(b.id) {
                    match self.kinematic_contact(b.id, b.x.len()) {
                        Some(f) => b.f_contact = f,
                        None => tracing::debug!(
                            "frame at step {step}: no per-node contact forces on kinematic body {}",
                            b.id
                        ),
                    }
                }
                if let Some(sink) = sink.as_mut() {
                    sink.frame_body(b).map_err(MasterError::sink)?;
                }
            }
        }
        if let Some(sink) = sink {
            sink.frame_end().map_err(MasterError::sink)?;
        }
        Ok(hashed.then(|| hash.finish()))
    }

    /// One round of a frame's pieces: every worker that holds no received piece gets
    /// its next one asked of it (all at once); the replies, checked to hold the bodies
    /// asked for, go into `ready` by piece index.
    fn frame_round(
        &mut self,
        pieces: &[Piece],
        queues: &mut [VecDeque<usize>],
        ready: &mut BTreeMap<usize, (usize, Vec<FrameBody>)>,
    ) -> Result<(), MasterError> {
        let nw = self.links.len();
        let mut cmds = vec![Vec::new(); nw];
        // the piece asked of each worker and its bodies (the queues hold worker pieces)
        let mut asked: Vec<Option<(usize, &[u32])>> = vec![None; nw];
        for (w, q) in queues.iter_mut().enumerate() {
            if ready.values().any(|(hw, _)| *hw == w) {
                continue;
            }
            if let Some(i) = q.pop_front() {
                if let Piece::Worker(_, ids) = &pieces[i] {
                    cmds[w].push(Command::Frame(ids.clone()));
                    asked[w] = Some((i, ids));
                }
            }
        }
        for (w, mut replies) in self.exchange(cmds)?.into_iter().enumerate() {
            let Some((i, ids)) = asked[w] else { continue };
            let Some(Reply::Frame(bodies)) = replies.pop() else {
                return Err(self.bad_reply(w, "Frame"));
            };
            if !bodies.iter().map(|b| b.id).eq(ids.iter().copied()) {
                return Err(self.worker_error(
                    w,
                    LinkError::Protocol("a frame piece holds other bodies than asked".into()),
                ));
            }
            ready.insert(i, (w, bodies));
        }
        Ok(())
    }

    /// Whether an output time is reached at `time` (one rule for the frame and for the
    /// step before it, which asks for the forces on kinematic bodies).
    pub(super) fn frame_due(&self, time: f64) -> bool {
        self.output_interval > 0.0
            && time >= (self.frames as f64) * self.output_interval * (1.0 - TIME_EPS)
    }

    /// The contact force on each node of kinematic body `id` from the last pass: the
    /// pairs' per-node forces summed in pair order (the copies that felt them may sit in
    /// several groups on several workers). None when the last report did not carry them.
    fn kinematic_contact(&self, id: u32, nodes: usize) -> Option<Vec<crash_core::Vec3>> {
        if !self.kin_nodes {
            return None;
        }
        let mut f = vec![crash_core::Vec3::zeros(); nodes];
        for s in &self.contacts {
            let sides = [(s.a, &s.kin_a), (s.b, &s.kin_b)];
            // a self pair has one side (a kinematic body has none at all)
            for (_, l) in sides
                .iter()
                .take(if s.a == s.b { 1 } else { 2 })
                .filter(|x| x.0 == id)
            {
                for &(n, fn_) in &l.nodes {
                    if let Some(slot) = f.get_mut(n as usize) {
                        *slot += fn_;
                    }
                }
            }
        }
        Some(f)
    }

    /// Frame at the start, whenever an output time is reached, and at the end.
    pub(super) fn output(&mut self, sink: &mut dyn Sink, force: bool) -> Result<(), MasterError> {
        let time = self.clock.time;
        let due = self.frame_due(time);
        let step = self.clock.step;
        if self.last_frame_step == Some(step) {
            // this step's frame is out; a forced one needs its hash (a periodic frame
            // just before a stop request): the bodies are asked for again and hashed,
            // the frame is not written twice
            if force && self.hashed_step != Some(step) {
                let t = Instant::now();
                if let Some(h) = self.stream_frame(None, true)? {
                    self.stats.final_hash = h;
                    self.hashed_step = Some(step);
                }
                self.stats.stages.output_ns += ns(t);
            }
            return Ok(());
        } else if !(force || due) {
            return Ok(());
        }
        let t = Instant::now();
        let _s = tracing::debug_span!("output").entered();
        if self.frames_from_parts() {
            self.flush_split_contact()?;
        } else {
            self.assemble_splits()?;
        }
        // the split groups' pending contact pass has run: its rows
        self.release_rows(sink)?;
        // Only the frame the run ends on is hashed (the summary's final state hash): the
        // hash goes byte by byte over every node's x, v, w (FNV-1a, about 1 ms for the
        // showcase's 14 000 nodes), which on every frame cost the step loop about 1.5 %
        // with frames every 50 steps (docs/performance-history.md, session 9).
        let hashed = force || self.finished();
        if let Some(h) = self.stream_frame(Some(&mut *sink), hashed)? {
            self.stats.final_hash = h;
            self.hashed_step = Some(step);
        }
        self.write_groups(sink)?;
        self.last_frame_step = Some(step);
        if self.output_interval > 0.0 {
            // the next frame is the first whose time lies beyond now: in closed form, so
            // an interval far below the step costs nothing
            let due = (time * (1.0 + TIME_EPS) / self.output_interval).floor();
            let next = if due < u64::MAX as f64 {
                due as u64 + 1
            } else {
                u64::MAX
            };
            self.frames = next.max(self.frames + 1);
        }
        self.stats.frames += 1;
        self.stats.stages.output_ns += ns(t);
        Ok(())
    }
}
