//! A split group's frame from its parts (protocol v19): every holder sends the shares
//! of the parts it computes (`crash_io::PartFrame`: owned nodes, elements held) and the
//! master scatters them into each body's frame, taken from the body as it was split
//! (`Master::skeletons`: what the definition gives, the rest overwritten). So a frame
//! of a split group needs no assembly of whole bodies on their home (the parts' full
//! states up to the master and down again, then the whole frame on one worker): every
//! holder computes its share at once. The shares cover every node once and every
//! element at least once (a cut element is held by two parts, with the same bits),
//! which `FrameFromParts` checks, so no value of the kept frame can stand in a frame.

use super::Master;
use crate::error::MasterError;
use crash_io::{FrameBody, FrameFromParts};
use crash_link::{BodyLoad, Command, Reply, WorkerLink};
use std::collections::BTreeMap;

impl<L: WorkerLink> Master<'_, L> {
    /// Keep the frame of each body of a group being split (`bodies`, as the home
    /// unloaded them): the skeleton of its frames while it is split.
    pub(super) fn keep_skeletons(&mut self, bodies: &[BodyLoad]) {
        for b in bodies {
            if self.skeletons.contains_key(&b.id) {
                continue;
            }
            if let Ok(body) = b.clone().into_body(None) {
                self.skeletons.insert(b.id, FrameBody::capture(&body));
            }
        }
    }

    /// Whether the split groups' frames come from their parts: every split body has a
    /// skeleton (a body split before a resume has none until it is split again).
    pub(super) fn frames_from_parts(&self) -> bool {
        !self.splits.is_empty()
            && self
                .splits
                .iter()
                .flat_map(|s| &s.ids)
                .all(|id| self.skeletons.contains_key(id))
    }

    /// The frames of every split body from their parts' shares (the pending contact
    /// passes have run), by body id.
    pub(super) fn part_frames(&mut self) -> Result<BTreeMap<u32, FrameBody>, MasterError> {
        let ids: Vec<u32> = self
            .splits
            .iter()
            .flat_map(|s| s.ids.iter().copied())
            .collect();
        let cmds = self.to_holders(|| Command::PartFrames(ids.clone()));
        let mut out: BTreeMap<u32, FrameFromParts> = ids
            .iter()
            .filter_map(|id| Some((*id, FrameFromParts::new(self.skeletons.get(id)?.clone()))))
            .collect();
        for (w, r) in self.exchange(cmds)?.into_iter().enumerate() {
            for reply in r {
                let Reply::PartFrames(shares) = reply else {
                    return Err(self.bad_reply(w, "PartFrames"));
                };
                for p in shares {
                    let Some(f) = out.get_mut(&p.id) else {
                        return Err(self.implausible(w, &format!("a frame share of body {}", p.id)));
                    };
                    if let Err(e) = f.fill(&p) {
                        return Err(self.implausible(w, &format!("body {}: {e}", p.id)));
                    }
                }
            }
        }
        let mut frames = BTreeMap::new();
        for (id, f) in out {
            match f.finish() {
                Ok(f) => frames.insert(id, f),
                Err(e) => return Err(self.implausible(self.split_home(id), &e)),
            };
        }
        Ok(frames)
    }
}
