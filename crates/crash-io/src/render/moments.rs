//! The moments that matter in a run, picked from the contact-force history: first
//! contact, peak total contact force, separation; the contact sheet shows the frames
//! nearest to them (and the start and the end).

use crate::history::ContactRow;

/// Total contact force over time: one value per record time (0 where no pair touches).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ForceSeries {
    pub time: Vec<f64>,
    /// Sum over body pairs of the pair's normal force [N].
    pub total: Vec<f64>,
}

impl ForceSeries {
    /// From contacts.csv rows (one per touching pair per step) on the time base `times`
    /// (energy.csv's: every step, so steps without a row count as zero force). Times of
    /// rows missing from `times` are added; the result is sorted by time.
    pub fn from_rows(times: &[f64], rows: &[ContactRow]) -> Self {
        let mut t: Vec<f64> = times
            .iter()
            .chain(rows.iter().map(|r| &r.time))
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        t.sort_by(f64::total_cmp);
        t.dedup();
        let mut total = vec![0.0; t.len()];
        for r in rows.iter().filter(|r| r.force.is_finite()) {
            if let Ok(k) = t.binary_search_by(|v| v.total_cmp(&r.time)) {
                total[k] += r.force;
            }
        }
        Self { time: t, total }
    }
}

/// Indices into a force series of the moments that matter (None: it did not happen).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct KeyMoments {
    /// First record with a nonzero force.
    pub first_contact: Option<usize>,
    /// Largest force (the first record of it on ties).
    pub peak: Option<usize>,
    /// First record after the peak where the force is back to zero.
    pub separation: Option<usize>,
}

/// Pick the key moments of `force` (values per record; NaN counts as no force).
pub fn key_moments(force: &[f64]) -> KeyMoments {
    let touching = |v: f64| v.is_finite() && v > 0.0;
    let first_contact = force.iter().position(|&v| touching(v));
    let peak = first_contact.map(|first| {
        (first..force.len()).fold(first, |best, k| {
            if touching(force[k]) && force[k] > force[best] {
                k
            } else {
                best
            }
        })
    });
    let separation = peak.and_then(|p| (p + 1..force.len()).find(|&k| !touching(force[k])));
    KeyMoments {
        first_contact,
        peak,
        separation,
    }
}

/// Why a frame is on the sheet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reason {
    Start,
    FirstContact,
    PeakForce,
    Separation,
    End,
}

impl Reason {
    pub fn text(self) -> &'static str {
        match self {
            Reason::Start => "start",
            Reason::FirstContact => "first contact",
            Reason::PeakForce => "peak contact force",
            Reason::Separation => "separation",
            Reason::End => "end",
        }
    }
}

/// One panel of the sheet: a frame and the moments it stands for.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Index into the frame list.
    pub frame: usize,
    /// The time of the moment (not of the frame) [s]: the first of its reasons.
    pub moment_time: f64,
    pub reasons: Vec<Reason>,
}

impl Panel {
    /// "first contact, peak contact force".
    pub fn label(&self) -> String {
        let v: Vec<&str> = self.reasons.iter().map(|r| r.text()).collect();
        v.join(", ")
    }
}

/// Index of the frame time nearest to `t` (the earlier one on ties); None if empty.
pub fn nearest(frame_times: &[f64], t: f64) -> Option<usize> {
    (0..frame_times.len()).min_by(|&a, &b| {
        (frame_times[a] - t)
            .abs()
            .total_cmp(&(frame_times[b] - t).abs())
            .then(a.cmp(&b))
    })
}

/// Panels for the start, the key moments of `series` and the end, mapped to the
/// nearest frames; moments that fall on the same frame share one panel. In time order.
pub fn panels(frame_times: &[f64], series: &ForceSeries) -> Vec<Panel> {
    let (Some(&t0), Some(&t1)) = (frame_times.first(), frame_times.last()) else {
        return Vec::new();
    };
    let km = key_moments(&series.total);
    let at = |k: Option<usize>| k.and_then(|k| series.time.get(k).copied());
    let moments = [
        (Reason::Start, Some(t0)),
        (Reason::FirstContact, at(km.first_contact)),
        (Reason::PeakForce, at(km.peak)),
        (Reason::Separation, at(km.separation)),
        (Reason::End, Some(t1)),
    ];
    let mut out: Vec<Panel> = Vec::new();
    for (reason, t) in moments {
        let Some(t) = t else { continue };
        let Some(f) = nearest(frame_times, t) else {
            continue;
        };
        match out.iter_mut().find(|p| p.frame == f) {
            Some(p) => p.reasons.push(reason),
            None => out.push(Panel {
                frame: f,
                moment_time: t,
                reasons: vec![reason],
            }),
        }
    }
    out.sort_by_key(|p| p.frame);
    out
}
