//! The friction level against the driving speed and the stiffness
//! ([`friction_level`]): per run, the mean force, the force at slip onset and
//! where a slip ends, all from the one feature function, and whether the
//! level is a function of V, of k, or of neither — with one run per (k, V),
//! a level that depends on both at one cell cannot be told from a change of
//! the paper between runs.
//!
//! The yardstick is the level's own wander within a run: the sd of the mean
//! force over the record's parts ([`crate::Features::level_parts`]), the
//! friction along the 16 mm of track a run covers. A steady drive moves the
//! slider at V on average, so any law of the sliding speed (a
//! velocity-strengthening steady state, Heslot et al. 1994's branch at high
//! V; Bar-Sinai, Spatschek, Brener & Bouchbinder, J. Geophys. Res. Solid
//! Earth 119, 1738 (2014), on its generality) gives one level per V at every
//! spring, and a law of the set-up's spring one level per k at every V.

use crate::study::Measured;

/// Levels closer than this many yardsticks (2: twice the largest sd of a
/// run's parts) are the same level.
pub const SAME_LEVEL_SDS: f64 = 2.0;

/// What the level depends on, read from the runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LevelCause {
    /// The same level everywhere, within the yardstick.
    Constant,
    /// The same level at every V across the springs, different across V: a
    /// law of the speed (a candidate for the selection).
    Speed,
    /// The same level at every k across the speeds, different across k.
    Stiffness,
    /// Neither: levels differ at one V across the springs and at one k
    /// across the speeds (one run per (k, V): an interaction or a run).
    Neither,
    /// No V with two springs or no k with two speeds: nothing to compare.
    Untested,
}

/// The runs at one V across the springs (or at one k across the speeds)
/// and how far apart their mean forces are.
#[derive(Debug, Clone, PartialEq)]
pub struct Across {
    /// V in µm/s (across springs) or k in N/m (across speeds).
    pub at: f64,
    /// Run indices, in the runs' order.
    pub runs: Vec<usize>,
    /// Largest minus smallest mean force of these runs, F/(m g).
    pub range: f64,
}

/// [`friction_level`]'s reading.
#[derive(Debug, Clone, PartialEq)]
pub struct Level {
    /// Twice the largest sd of a run's parts' mean force, F/(m g) (the
    /// level's wander within a run; NaN when no run has parts).
    pub yardstick: f64,
    /// Per V with runs at two springs or more.
    pub at_speed: Vec<Across>,
    /// Per k with runs at two speeds or more.
    pub at_stiffness: Vec<Across>,
    pub cause: LevelCause,
}

/// The level of `runs` against V and k (see the module docs).
pub fn friction_level(runs: &[Measured]) -> Level {
    let sd = runs.iter().map(|r| r.features.level_parts.sd).filter(|x| x.is_finite()).fold(f64::NAN, f64::max);
    let yardstick = SAME_LEVEL_SDS * sd;
    let group = |key: &dyn Fn(&Measured) -> f64| -> Vec<Across> {
        let mut keys: Vec<f64> = runs.iter().map(key).collect();
        keys.sort_by(f64::total_cmp);
        keys.dedup();
        keys.into_iter()
            .filter_map(|at| {
                let idx: Vec<usize> = (0..runs.len()).filter(|&i| key(&runs[i]) == at).collect();
                let levels = idx.iter().map(|&i| runs[i].features.mean_force);
                let (lo, hi) = levels.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
                (idx.len() >= 2).then_some(Across { at, runs: idx, range: hi - lo })
            })
            .collect()
    };
    let at_speed = group(&|r| r.drive_speed_um_s);
    let at_stiffness = group(&|r| r.stiffness_n_m);
    let same = |a: &[Across]| a.iter().all(|x| x.range <= yardstick);
    let cause = if at_speed.is_empty() || at_stiffness.is_empty() || !yardstick.is_finite() {
        LevelCause::Untested
    } else {
        match (same(&at_speed), same(&at_stiffness)) {
            (true, true) => LevelCause::Constant,
            (true, false) => LevelCause::Speed,
            (false, true) => LevelCause::Stiffness,
            (false, false) => LevelCause::Neither,
        }
    };
    Level { yardstick, at_speed, at_stiffness, cause }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{Features, Spread};

    fn run(k: f64, v: f64, level: f64) -> Measured {
        let mut features = Features::default_steady();
        features.mean_force = level;
        features.level_parts = Spread::of(&[level - 0.01, level + 0.01, level - 0.01, level + 0.01]);
        Measured {
            name: format!("k{k}-v{v}"),
            stiffness_n_m: k,
            drive_speed_um_s: v,
            duration_s: 10.0,
            sample_rate_hz: 2000.0,
            features,
            spectral_period_s: f64::NAN,
            force_step: f64::NAN,
        }
    }

    fn cause(levels: [[f64; 3]; 2]) -> LevelCause {
        let runs: Vec<Measured> = [168.0, 2254.0]
            .iter()
            .zip(levels)
            .flat_map(|(&k, l)| [42.0, 1100.0, 4300.0].iter().zip(l).map(move |(&v, x)| run(k, v, x)))
            .collect();
        friction_level(&runs).cause
    }

    #[test]
    fn reads_a_law_of_the_speed_of_the_spring_or_of_neither() {
        // Parts' sd 0.0115: the yardstick is 0.023.
        assert_eq!(cause([[0.33, 0.34, 0.33], [0.34, 0.33, 0.34]]), LevelCause::Constant);
        assert_eq!(cause([[0.30, 0.36, 0.45], [0.31, 0.37, 0.44]]), LevelCause::Speed);
        assert_eq!(cause([[0.30, 0.31, 0.30], [0.40, 0.41, 0.40]]), LevelCause::Stiffness);
        // One cell apart (the shipped runs' pattern): neither.
        assert_eq!(cause([[0.30, 0.33, 0.50], [0.37, 0.33, 0.35]]), LevelCause::Neither);
        let one = friction_level(&[run(168.0, 42.0, 0.3), run(168.0, 1100.0, 0.4)]);
        assert_eq!(one.cause, LevelCause::Untested);
        assert!((one.at_stiffness[0].range - 0.1).abs() < 1e-12 && one.at_speed.is_empty());
    }
}
