//! Output: when a frame is due, every worker sends what a frame shows of its bodies;
//! the master merges them in id order, hands the frame to the sink and drops it.

use super::{ns, Master, TIME_EPS};
use crate::error::MasterError;
use crate::sink::Sink;
use crash_io::{Frame, FrameBody};
use crash_link::{Command, Reply, WorkerLink};
use std::time::Instant;

impl<L: WorkerLink> Master<'_, L> {
    /// The frame of every body now, gathered from the workers.
    fn gather_frame(&mut self) -> Result<Frame, MasterError> {
        let nw = self.links.len();
        let replies = self.exchange((0..nw).map(|_| vec![Command::Frame]).collect())?;
        let mut all: Vec<FrameBody> = Vec::with_capacity(self.info.len());
        for (w, mut r) in replies.into_iter().enumerate() {
            match r.pop() {
                Some(Reply::Frame(bodies)) => all.extend(bodies),
                _ => return Err(self.bad_reply(w, "Frame")),
            }
        }
        let frame = Frame::from_bodies(self.clock.time, self.clock.step, all);
        let ids: Vec<u32> = frame.bodies.iter().map(|b| b.id).collect();
        if !ids.iter().copied().eq(self.info.iter().map(|i| i.id)) {
            return Err(MasterError::Incomplete {
                step: self.clock.step,
                what: "frame bodies",
                got: ids.len(),
                expected: self.info.len(),
            });
        }
        Ok(frame)
    }

    /// Frame at the start, whenever an output time is reached, and at the end.
    pub(super) fn output(&mut self, sink: &mut dyn Sink, force: bool) -> Result<(), MasterError> {
        let time = self.clock.time;
        let due = self.output_interval > 0.0
            && time >= (self.frames as f64) * self.output_interval * (1.0 - TIME_EPS);
        if !(force || due) || self.last_frame_step == Some(self.clock.step) {
            return Ok(());
        }
        let t = Instant::now();
        let _s = tracing::debug_span!("output").entered();
        let frame = self.gather_frame()?;
        self.stats.final_hash = frame.state_hash();
        sink.frame(&frame).map_err(MasterError::sink)?;
        self.last_frame_step = Some(self.clock.step);
        while (self.frames as f64) * self.output_interval <= time * (1.0 + TIME_EPS)
            && self.output_interval > 0.0
        {
            self.frames += 1;
        }
        self.stats.frames += 1;
        self.stats.stages.output_ns += ns(t);
        Ok(())
    }
}
