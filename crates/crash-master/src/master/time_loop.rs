//! The global time loop: start, one step, the end. Per step: Step{clock, dt} to every
//! worker, the barrier, global dt = safety x min stable dt (the core driver's rules, on
//! the reports in body-id order), MEIM update, migration, output.

use super::{ns, Master, TIME_EPS};
use crate::error::MasterError;
use crate::input::BodySource;
use crate::input::CostModel;
use crate::sink::Sink;
use crash_core::contact::BodyBox;
use crash_core::driver::{check_runaway, choose_dt, step_length};
use crash_core::{BodyBrief, Clock, Due, EnergyTotals, Fault};
use crash_link::{BodyLoad, Command, Setup, WorkerLink};
use std::time::Instant;

impl<L: WorkerLink> Master<'_, L> {
    pub(super) fn setup(&self) -> Setup {
        Setup {
            gravity: self.gravity,
            contact: self.contact,
            reactions: self.results.spcforc > 0.0,
            probes: std::sync::Arc::new(self.results.history.iter().map(|h| (h.0, h.1)).collect()),
        }
    }

    /// Bodies onto workers (each body's definition and state move to its worker, one
    /// body at a time: the master keeps none), forces of the initial configuration,
    /// first dt. The groups are split after (`Session::split`): the first rollback
    /// point is taken before, as whole groups (the same bits, without the assembly a
    /// split group's checkpoint needs).
    pub(crate) fn start(
        &mut self,
        bodies: BodySource,
        briefs: &[BodyBrief],
        sink: &mut dyn Sink,
    ) -> Result<(), MasterError> {
        // kept: a rollback may need a definition a survivor never received
        self.source = Some(bodies);
        let t0 = Instant::now();
        let boxes: Vec<BodyBox> = briefs.iter().map(|b| self.inflate(b.bbox())).collect();
        self.update_meim(&boxes);
        let placement = self.place_all();
        let bare: Vec<BodyBox> = briefs.iter().map(|b| b.bbox()).collect();
        self.plan_at_start(&bare);
        self.stats.stages.meim_ns += ns(t0);
        let t1 = Instant::now();
        let mut source = self.source.take();
        let loaded = self.load_all(&placement, |id| {
            let b = source
                .as_mut()
                .ok_or_else(|| MasterError::Input("no bodies".into()))?;
            Ok(BodyLoad::whole(b.take(id)?))
        });
        self.source = source;
        loaded?;
        let mut reports = self.reports_of(|| Command::Start, "Start")?;
        self.drop_shadows(&mut reports);
        self.stats.stages.migration_ns += ns(t1);
        self.kin_nodes = true; // the start always carries them
        self.gather(reports, None)?;
        let energy = self
            .ledger
            .update(EnergyTotals::sum(self.reports.iter().map(|r| &r.energy)));
        self.next_dt = self.choose_dt()?;
        self.dt0 = self.next_dt;
        self.stats.dt_min = f64::INFINITY;
        sink.energy(0, 0.0, &energy).map_err(MasterError::sink)?;
        sink.contact_stats(0, 0.0, &self.contacts)
            .map_err(MasterError::sink)?;
        sink.contacts(0, 0.0, &self.meim.pairs())
            .map_err(MasterError::sink)?;
        self.write_results(sink, None)?;
        self.output(sink, true)
    }

    /// The core's rule (`crash_core::driver::choose_dt`), shared by every loop.
    fn choose_dt(&self) -> Result<f64, Fault> {
        choose_dt(&self.cfg, &self.reports, self.dt0, self.clock.step)
    }

    pub(crate) fn finished(&self) -> bool {
        self.clock.time >= self.cfg.end_time * (1.0 - TIME_EPS)
    }

    /// One global step (the last one shortened to land on the end time).
    pub(crate) fn step(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        let _span = tracing::debug_span!("step", step = self.clock.step).entered();
        // workers that attached since the last step (newcomers.rs)
        self.admit_at_step()?;
        let (h, short) = step_length(self.next_dt, self.cfg.end_time - self.clock.time);
        if short {
            self.stats.last_dt = h;
        } else {
            self.stats.dt_min = self.stats.dt_min.min(h);
            self.stats.dt_max = self.stats.dt_max.max(h);
        }
        for l in self.links.iter_mut() {
            l.take_codec_ns(); // what earlier exchanges (loads, frames) spent
        }
        let t0 = Instant::now();
        let at = self.clock;
        // a frame follows this step: the forces on kinematic bodies come with the reports
        let after = at.after(h).time;
        let kin_nodes = self.frame_due(after) || after >= self.cfg.end_time * (1.0 - TIME_EPS);
        self.kin_nodes = kin_nodes;
        // reactions and history nodes only for a step whose rows are written
        let [_, _, nodout, spcforc] = self.rows_due(Some(at.time), after);
        let due = Due {
            reactions: spcforc,
            probes: nodout,
        };
        // split groups: the element steps for the contact pass the last step left
        let contact = std::mem::take(&mut self.split_contact);
        // split groups whose holders all take direct halo connections skip the relay
        let direct = !self.direct_failed
            && !self.splits.is_empty()
            && self.splits.iter().all(|s| s.direct());
        let reps = {
            let _s = tracing::debug_span!("barrier").entered();
            let mut reps = self.reports_of(
                || Command::Step {
                    at,
                    dt: h,
                    kin_nodes,
                    due,
                    contact: contact.clone(),
                    direct,
                },
                "Step",
            )?;
            // the split groups' contact statistics of the pass this Step ran first
            let merging = Instant::now();
            self.take_split_stats(&mut reps)?;
            self.merge_ns = ns(merging);
            // split groups: one more exchange (split.rs), and under the segment pass
            // a third, the contact pass
            self.relay_split(&mut reps, direct)?;
            self.contact_in_step(&mut reps)?;
            reps
        };
        let wall = ns(t0);
        // the last step's rows, if held for those statistics (held.rs)
        self.release_rows(sink)?;
        // a fault being replayed did not recur: its reporter lied (confirm.rs)
        self.replayed_without_fault(at.step);
        let slowest = reps
            .iter()
            .map(|r| r.compute_ns)
            .max()
            .unwrap_or(0)
            .min(wall);
        self.stats.stages.compute_ns += slowest;
        let per = &mut self.stats.worker_compute_ns;
        per.resize(per.len().max(reps.len()), 0);
        for (t, r) in per.iter_mut().zip(&reps) {
            *t += r.compute_ns;
        }
        self.stats.stages.barrier_ns += wall - slowest;
        let master_codec: u64 = self.links.iter_mut().map(|l| l.take_codec_ns()).sum();
        let worker_codec = reps.iter().map(|r| r.codec_ns).max().unwrap_or(0);
        self.stats
            .barrier
            .record(wall - slowest, master_codec, worker_codec, self.merge_ns);
        self.clock = self.clock.after(h);

        let t1 = Instant::now();
        let _s = tracing::debug_span!("meim").entered();
        self.gather(reps, Some((at, h)))?;
        if let Some(split) = self.split_now.take() {
            self.contacts.extend(split);
            self.contacts.sort_by_key(|c| (c.a, c.b));
        }
        let energy = self.ledger.record(
            EnergyTotals::sum(self.reports.iter().map(|r| &r.energy)),
            !short,
        );
        self.runaway(&energy)?;
        self.next_dt = self.choose_dt()?;
        self.check_margin()?;
        let (step, time) = (self.clock.step, self.clock.time);
        sink.energy(step, time, &energy)
            .map_err(MasterError::sink)?;
        if self.rows_wait() {
            let [_, rcforc, _, _] = self.rows_due(Some(at.time), time);
            self.hold_rows(rcforc);
        } else {
            sink.contact_stats(step, time, &self.contacts)
                .map_err(MasterError::sink)?;
        }
        self.write_results(sink, Some(at.time))?;
        let boxes: Vec<BodyBox> = self.reports.iter().map(|r| self.box_of(r)).collect();
        let changed = self.update_meim(&boxes);
        if changed {
            self.stats.group_changes += 1;
            sink.contacts(step, time, &self.meim.pairs())
                .map_err(MasterError::sink)?;
        }
        let periodic = self.opts.cost == CostModel::Measured
            && self.opts.rebalance_interval > 0
            && step.is_multiple_of(self.opts.rebalance_interval);
        self.stats.stages.meim_ns += ns(t1);
        drop(_s);
        // a split group stays where it is until the groups change (no periodic moves)
        let periodic = periodic && self.splits.is_empty();
        // and while bodies only leave groups (every MEIM group still lies within a
        // group the workers hold, so every contact is computed): merging a split back
        // and cutting it again costs tens of milliseconds, carrying a body that left
        // costs its own work only (the floor's spheres bouncing off: 12 re-splits in
        // 53 steps). The next change that needs a regroup takes the MEIM as it is then.
        let kept =
            changed && !self.rebalance && !self.splits.is_empty() && self.layout_holds_meim();
        if kept {
            self.stats.splits_kept += 1;
            self.log_kept_splits();
        } else if changed || periodic || self.rebalance {
            self.rebalance = false;
            let _s = tracing::debug_span!("migration").entered();
            let t2 = Instant::now();
            self.unsplit()?;
            self.migrate(changed)?;
            self.split_groups()?;
            self.announce();
            self.stats.stages.migration_ns += ns(t2);
        }
        if changed {
            self.write_groups(sink)?;
        }
        self.output(sink, false)
    }

    /// The core's runaway guard (`crash_core::driver::check_runaway`).
    fn runaway(&mut self, energy: &EnergyTotals) -> Result<(), Fault> {
        check_runaway(
            &self.cfg,
            &mut self.ledger,
            energy,
            &self.reports,
            self.clock.step,
        )
    }

    /// The margin argument, checked: no contact body may move more in one step than
    /// the MEIM inflation beyond the contact search box allows.
    fn check_margin(&self) -> Result<(), MasterError> {
        for (r, inf) in self.reports.iter().zip(&self.info) {
            if inf.meshes && r.max_move > inf.allowed {
                return Err(MasterError::Margin {
                    step: self.clock.step,
                    body: r.id,
                    moved: r.max_move,
                    allowed: inf.allowed,
                    margin: 2.0 * inf.allowed
                        / (self.opts.margin_factor - 1.0).max(f64::MIN_POSITIVE),
                    factor: self.opts.margin_factor,
                });
            }
        }
        Ok(())
    }

    /// Where the run stands, into the statistics (also after a fault: steps done, time
    /// reached, the energy figure so far).
    pub(crate) fn record_progress(&mut self) {
        self.stats.steps = self.clock.step;
        self.stats.time = self.clock.time;
        self.stats.workers = self.live_count();
        self.stats.max_energy_error = self.ledger.max_error();
        if !self.stats.dt_min.is_finite() && self.stats.last_dt > 0.0 {
            // only a shortened step was taken
            self.stats.dt_min = self.stats.last_dt;
            self.stats.dt_max = self.stats.last_dt;
        }
    }

    /// Final frame (the state hash) and statistics.
    pub(crate) fn finish(&mut self, sink: &mut dyn Sink) -> Result<(), MasterError> {
        self.settle_rows(sink)?;
        self.output(sink, true)?;
        self.record_progress();
        let b = &self.stats.barrier;
        let [mc, wc, mg, ww] = b.parts_us();
        let steps = self.stats.steps.max(1) as f64;
        tracing::info!(
            "barrier per step: median {:.1} us (mean: master encode/decode {mc:.1}, worker decode/encode {wc:.1}, master merge {mg:.1}, wire and wake-up {ww:.1}); master work {:.1} us",
            b.median_us(),
            self.stats.stages.meim_ns as f64 / steps / 1e3
        );
        self.stats.final_groups = self
            .meim
            .groups()
            .iter()
            .flat_map(|g| self.group_shares(g))
            .map(|(w, ids, _)| (ids, w))
            .collect();
        Ok(())
    }

    /// The clock after the last step taken.
    pub(crate) fn clock(&self) -> Clock {
        self.clock
    }
}
