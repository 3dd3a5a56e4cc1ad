//! The handshake rule: master and worker speak the same protocol version or refuse
//! each other with a message that names both.

use thiserror::Error;

/// Version of the master <-> worker protocol. Raise it whenever a message changes
/// meaning. v2: bodies split into definition and state, the clock in Step and Load,
/// frames and states requested apart. v3: the master's Challenge opens the session and
/// the worker's Hello carries a proof of the shared secret. v4: the contact settings
/// carry the closing-speed rule, faults include a pass-through. v5: heartbeats on a
/// connection of their own (Welcome carries the session token), Reset for a rollback.
/// v6: read-only copies of kinematic bodies (Regroup lists them per group, Load of
/// copies, Unload that keeps), contact statistics carry the loads on kinematic bodies.
/// v7: load curves in body definitions, support reactions and history nodes (Setup asks,
/// reports carry them) for spcforc.csv and nodout.csv. v8: a reaction carries its
/// resultant moment about the origin too (stride 9); Step says whether reactions and
/// history nodes are due (sent only for steps whose result rows are written); velocity
/// programs carry their kind (prescribed displacement, stride 8). v9: groups split over
/// workers (Split, Share, Halo, Contact, Parts, Assemble, Unsplit; Report.parts).
/// v10: a split step is two exchanges: Halo is answered by a Report (the shares and
/// Report.part_dts), Step carries the element steps for the pending contact pass,
/// Contact runs it before an assembly (Ack); the PartDts reply is gone. v11: a part
/// state carries x, v, w at the part's export nodes only (every owned node in the step
/// before a view build; v too under the closing-speed rule), its box and its largest
/// distance from where the views were built. v12: quad reference data in stride 11
/// (what the element stores: gradients of nodes 3 and 4, h.X, h.Y, area, e0, bb; was 19).
/// v13: a part state's x, v, w travel as one block of raw little-endian doubles.
/// v14: the step lane (Welcome.lane_port; commands and replies as length-prefixed
/// frames on a plain TCP connection of their own, `lane`).
/// v15: split groups send no velocities for the closing speed: parts send their
/// momentum on a fixed quantum, holders their largest relative speeds per pair
/// (PartDts.pair_*), which the master merges and sends back with the next step.
/// v16: contact statistics carry their exact force sums (ContactStats.tally); a split
/// group's holders report their share of its statistics (Report.split_contacts) with
/// the Step that runs the pending contact pass, and Contact is answered by a Report.
/// v17: a Fault reply carries the worker's share of that pass when it ran
/// (Failure.split_contacts), so the step before a fault keeps its contact rows.
/// v18: the holders of split groups exchange their part states directly (Hello's
/// peer port, Welcome's peer key, SplitSpec's workers and peers, Step's direct,
/// Report's halo, PeerHalo frames between workers).
/// v19: a split group's frame comes from its parts (PartFramesRequest -> PartFrames),
/// with no assembly of whole bodies.
/// v20: a Share without bodies splits the group the worker holds (a split planned at
/// the start: every holder is loaded with the group and starts it; slot 0 is the home).
/// v21: a split group under the segment pass runs its contact pass in the step (a
/// Contact after the Halo), whose Report carries the stiffening step per body
/// (Report.limit_ids, limit_dts).
/// v22: the segment pass runs one side by default (the finer surface's points, full
/// weight; ContactConfig.sides "finer" or "both"): a v21 peer would run both sides.
/// v23: the segment pass's default sides are "auto" (one way only where one surface is
/// clearly finer; an empty ContactConfig.sides now means "auto"): a v22 peer would run
/// one way between meshes of about one size.
pub const PROTOCOL_VERSION: u32 = 23;

#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("protocol version mismatch: {peer} speaks crash protocol v{theirs}, this {me} speaks v{PROTOCOL_VERSION}; run matching versions of crash-master and crash-worker")]
pub struct VersionError {
    pub peer: String,
    pub theirs: u32,
    pub me: &'static str,
}

/// Accept a peer that speaks `theirs`. `peer` and `me` name the two ends in the error.
pub fn check_version(theirs: u32, peer: &str, me: &'static str) -> Result<(), VersionError> {
    if theirs == PROTOCOL_VERSION {
        Ok(())
    } else {
        Err(VersionError {
            peer: peer.to_string(),
            theirs,
            me,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_different_version_is_refused_naming_both() {
        assert!(check_version(PROTOCOL_VERSION, "w", "master").is_ok());
        let e = check_version(PROTOCOL_VERSION + 1, "worker a:1", "master").expect_err("refused");
        let s = e.to_string();
        assert!(
            s.contains(&format!("v{}", PROTOCOL_VERSION + 1))
                && s.contains(&format!("v{PROTOCOL_VERSION}")),
            "{s}"
        );
    }
}
