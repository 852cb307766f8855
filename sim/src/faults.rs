//! A fault-injecting wire: what a bad cable, a noisy drive or a pulled
//! connector does to EtherCAT frames, reproducibly (seeded).
//!
//! The virtual link of `master-test` and the raw-socket runner put a
//! [`FaultInjector`] between the master and the slaves. For every frame it
//! decides a [`Fate`]:
//!
//! * **drop** before the slaves (they never see it) or after them (they
//!   acted on it, the reply is lost);
//! * **corrupt** (one bit flipped, bad FCS) or **truncate** (a runt): an
//!   ESC detects the bad checksum, counts an RX error (0x0300) and does not
//!   act on the frame; the master discards what comes back. Both are thus
//!   "seen and counted by the first slave, lost for everyone";
//! * **duplicate**: the slaves process the frame twice (a switch or a
//!   retrying NIC), the master gets two replies;
//! * **delay** by a time, or **reorder** (held back behind the next frame);
//! * **link down** for scheduled windows (cable pulled): nothing passes,
//!   the slaves keep running on their own time, so their watchdogs see the
//!   loss exactly as on a real line.
//!
//! Configured by a text such as
//! `drop=1%,corrupt=0.1%,dup=0.1%,delay=5ms@1%,reorder=0.5%,down=2s+500ms,from=3s,seed=7`
//! ([`FaultConfig::from_str`]; `from` delays the random faults so a master
//! can bring the line up on a clean wire first).

use rand::rngs::SmallRng;
use rand::{Rng as _, SeedableRng as _};
use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;
use std::time::Duration;

/// What happens to one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fate {
    /// Passes unharmed.
    Deliver,
    /// Lost before the slaves.
    DropBefore,
    /// The slaves process it; the reply is lost.
    DropAfter,
    /// A bad checksum (bit flip or runt): the first slave counts an RX
    /// error, nobody acts on it, the master gets nothing valid.
    Corrupt,
    /// Processed twice; two replies.
    Duplicate,
    /// Delivered after this much extra time.
    Delay(Duration),
    /// Held back and delivered after the next frame.
    Reorder,
    /// The link is down (a scheduled window): lost before the slaves.
    LinkDown,
}

/// Rates (0.0..=1.0 per frame), the delay, the link-down windows and the
/// seed of a faulty wire.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultConfig {
    /// Frames lost (half before, half after the slaves).
    pub drop: f64,
    /// Frames with a bad checksum (bit flips and runts).
    pub corrupt: f64,
    /// Frames duplicated.
    pub duplicate: f64,
    /// Frames delayed, and by how much.
    pub delay: (Duration, f64),
    /// Frames reordered with the next one.
    pub reorder: f64,
    /// Link-down windows: (start after the link comes up, duration).
    pub down: Vec<(Duration, Duration)>,
    /// The random faults start this long after the link comes up (a
    /// master brings the line up on a clean wire first).
    pub from: Duration,
    /// Seed of the random decisions.
    pub seed: u64,
}

impl Default for FaultConfig {
    fn default() -> Self {
        FaultConfig {
            drop: 0.0,
            corrupt: 0.0,
            duplicate: 0.0,
            delay: (Duration::ZERO, 0.0),
            reorder: 0.0,
            down: Vec::new(),
            from: Duration::ZERO,
            seed: 1,
        }
    }
}

/// Why a fault configuration text was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "bad fault setting '{item}': {why} (e.g. drop=1%,corrupt=0.1%,dup=0.1%,delay=5ms@1%,reorder=0.5%,down=2s+500ms,from=3s,seed=7)"
)]
pub struct FaultConfigError {
    /// The item that could not be read.
    pub item: String,
    /// What is wrong with it.
    pub why: &'static str,
}

fn rate(s: &str) -> Option<f64> {
    let v = match s.strip_suffix('%') {
        Some(p) => p.trim().parse::<f64>().ok()? / 100.0,
        None => s.trim().parse::<f64>().ok()?,
    };
    (0.0..=1.0).contains(&v).then_some(v)
}

/// `5ms`, `2s`, `250us`, `1.5s`.
fn duration(s: &str) -> Option<Duration> {
    let s = s.trim();
    let (num, scale) = if let Some(n) = s.strip_suffix("ms") {
        (n, 1e-3)
    } else if let Some(n) = s.strip_suffix("us") {
        (n, 1e-6)
    } else if let Some(n) = s.strip_suffix('s') {
        (n, 1.0)
    } else {
        return None;
    };
    let v: f64 = num.trim().parse().ok()?;
    (0.0..1e6)
        .contains(&v)
        .then(|| Duration::from_secs_f64(v * scale))
}

impl FromStr for FaultConfig {
    type Err = FaultConfigError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let mut c = FaultConfig::default();
        for item in text.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let bad = |why| FaultConfigError {
                item: item.to_string(),
                why,
            };
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| bad("expected KEY=VALUE"))?;
            let r = || rate(value).ok_or_else(|| bad("a rate is 0..=1 or 0%..=100%"));
            match key.trim() {
                "drop" => c.drop = r()?,
                "corrupt" => c.corrupt = r()?,
                "dup" | "duplicate" => c.duplicate = r()?,
                "reorder" => c.reorder = r()?,
                "delay" => {
                    let (d, p) = value
                        .split_once('@')
                        .ok_or_else(|| bad("delay=TIME@RATE"))?;
                    let d = duration(d).ok_or_else(|| bad("a time is e.g. 5ms, 250us, 1.5s"))?;
                    c.delay = (
                        d,
                        rate(p).ok_or_else(|| bad("a rate is 0..=1 or 0%..=100%"))?,
                    );
                }
                "down" => {
                    let (at, len) = value
                        .split_once('+')
                        .ok_or_else(|| bad("down=START+LENGTH"))?;
                    let at = duration(at).ok_or_else(|| bad("a time is e.g. 5ms, 250us, 1.5s"))?;
                    let len =
                        duration(len).ok_or_else(|| bad("a time is e.g. 5ms, 250us, 1.5s"))?;
                    c.down.push((at, len));
                }
                "seed" => {
                    c.seed = value
                        .trim()
                        .parse()
                        .map_err(|_| bad("a seed is an integer"))?
                }
                "from" => {
                    c.from =
                        duration(value).ok_or_else(|| bad("a time is e.g. 5ms, 250us, 1.5s"))?;
                }
                _ => {
                    return Err(bad(
                        "unknown kind (drop, corrupt, dup, delay, reorder, down, from, seed)",
                    ));
                }
            }
        }
        let total = c.drop + c.corrupt + c.duplicate + c.delay.1 + c.reorder;
        if total > 1.0 {
            return Err(FaultConfigError {
                item: text.to_string(),
                why: "the rates add up to more than 100 %",
            });
        }
        Ok(c)
    }
}

impl fmt::Display for FaultConfig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "drop={}%,corrupt={}%,dup={}%,delay={:?}@{}%,reorder={}%",
            self.drop * 100.0,
            self.corrupt * 100.0,
            self.duplicate * 100.0,
            self.delay.0,
            self.delay.1 * 100.0,
            self.reorder * 100.0
        )?;
        for (at, len) in &self.down {
            write!(f, ",down={at:?}+{len:?}")?;
        }
        if !self.from.is_zero() {
            write!(f, ",from={:?}", self.from)?;
        }
        write!(f, ",seed={}", self.seed)
    }
}

/// What the injector did so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FaultStats {
    /// Frames offered.
    pub frames: u64,
    /// Dropped before the slaves.
    pub dropped_before: u64,
    /// Dropped after the slaves.
    pub dropped_after: u64,
    /// Corrupted (bad checksum).
    pub corrupted: u64,
    /// Duplicated.
    pub duplicated: u64,
    /// Delayed.
    pub delayed: u64,
    /// Reordered.
    pub reordered: u64,
    /// Lost while the link was down.
    pub link_down: u64,
}

impl FaultStats {
    /// Frames that did not reach the master as one valid reply.
    pub fn lost(&self) -> u64 {
        self.dropped_before + self.dropped_after + self.corrupted + self.link_down
    }
}

/// Decides the [`Fate`] of each frame.
#[derive(Debug, Clone)]
pub struct FaultInjector {
    config: FaultConfig,
    rng: SmallRng,
    stats: FaultStats,
    /// Fates forced for given frame numbers (0 = the first frame offered).
    forced: BTreeMap<u64, Fate>,
}

impl FaultInjector {
    /// An injector for `config`.
    pub fn new(config: FaultConfig) -> Self {
        let rng = SmallRng::seed_from_u64(config.seed);
        FaultInjector {
            config,
            rng,
            stats: FaultStats::default(),
            forced: BTreeMap::new(),
        }
    }

    /// Frames offered so far (the number the next frame gets).
    pub fn frames(&self) -> u64 {
        self.stats.frames
    }

    /// Forces the fate of frame number `frame` (see [`Self::frames`]): a
    /// schedule, for tests that interrupt a transfer at every frame.
    pub fn force(&mut self, frame: u64, fate: Fate) {
        self.forced.insert(frame, fate);
    }

    /// Pulls the cable at `at` (time since the link came up) for `len`.
    pub fn pull_cable(&mut self, at: Duration, len: Duration) {
        self.config.down.push((at, len));
    }

    /// Replaces the rates, windows and seed from now on (a test brings a
    /// line up on a clean wire, then makes it bad).
    pub fn set_config(&mut self, config: FaultConfig) {
        self.rng = SmallRng::seed_from_u64(config.seed);
        self.config = config;
    }

    /// Ends every fault from now on (rates to zero, schedule and windows
    /// cleared).
    pub fn heal(&mut self) {
        let seed = self.config.seed;
        self.config = FaultConfig {
            seed,
            ..FaultConfig::default()
        };
        self.forced.clear();
    }

    /// The configuration.
    pub fn config(&self) -> &FaultConfig {
        &self.config
    }

    /// Whether the link is up at `since_start` (time since the link came
    /// up).
    pub fn link_up(&self, since_start: Duration) -> bool {
        !self
            .config
            .down
            .iter()
            .any(|(at, len)| since_start >= *at && since_start < *at + *len)
    }

    /// The fate of the next frame, offered at `since_start`.
    pub fn fate(&mut self, since_start: Duration) -> Fate {
        let number = self.stats.frames;
        self.stats.frames += 1;
        if !self.link_up(since_start) {
            self.stats.link_down += 1;
            return Fate::LinkDown;
        }
        if let Some(f) = self.forced.remove(&number) {
            self.count(f);
            return f;
        }
        if since_start < self.config.from {
            return Fate::Deliver;
        }
        let c = &self.config;
        let x: f64 = self.rng.random();
        let mut edge = c.drop;
        if x < edge {
            return if self.rng.random_bool(0.5) {
                self.stats.dropped_before += 1;
                Fate::DropBefore
            } else {
                self.stats.dropped_after += 1;
                Fate::DropAfter
            };
        }
        edge += c.corrupt;
        if x < edge {
            self.stats.corrupted += 1;
            return Fate::Corrupt;
        }
        edge += c.duplicate;
        if x < edge {
            self.stats.duplicated += 1;
            return Fate::Duplicate;
        }
        edge += c.delay.1;
        if x < edge {
            self.stats.delayed += 1;
            return Fate::Delay(c.delay.0);
        }
        edge += c.reorder;
        if x < edge {
            self.stats.reordered += 1;
            return Fate::Reorder;
        }
        Fate::Deliver
    }

    fn count(&mut self, f: Fate) {
        let s = &mut self.stats;
        match f {
            Fate::Deliver => {}
            Fate::DropBefore => s.dropped_before += 1,
            Fate::DropAfter => s.dropped_after += 1,
            Fate::Corrupt => s.corrupted += 1,
            Fate::Duplicate => s.duplicated += 1,
            Fate::Delay(_) => s.delayed += 1,
            Fate::Reorder => s.reordered += 1,
            Fate::LinkDown => s.link_down += 1,
        }
    }

    /// What was injected so far.
    pub fn stats(&self) -> FaultStats {
        self.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fault_texts_parse_with_percent_and_times() {
        let c: FaultConfig =
            "drop=1%,corrupt=0.001,dup=0.1%,delay=5ms@1%,reorder=0.5%,down=2s+500ms,seed=7"
                .parse()
                .unwrap();
        assert!((c.drop - 0.01).abs() < 1e-12);
        assert!((c.corrupt - 0.001).abs() < 1e-12);
        assert!((c.duplicate - 0.001).abs() < 1e-12);
        assert_eq!(c.delay.0, Duration::from_millis(5));
        assert_eq!(
            c.down,
            vec![(Duration::from_secs(2), Duration::from_millis(500))]
        );
        assert_eq!(c.seed, 7);
        assert_eq!("".parse::<FaultConfig>().unwrap(), FaultConfig::default());
        let late: FaultConfig = "drop=100%,from=1s".parse().unwrap();
        let mut f = FaultInjector::new(late);
        assert_eq!(f.fate(Duration::from_millis(999)), Fate::Deliver);
        assert!(matches!(
            f.fate(Duration::from_secs(1)),
            Fate::DropBefore | Fate::DropAfter
        ));
    }

    #[test]
    fn bad_fault_texts_name_the_item() {
        for (text, why) in [
            ("drop", "KEY=VALUE"),
            ("drop=2", "rate"),
            ("drop=-1%", "rate"),
            ("drop=x", "rate"),
            ("delay=5ms", "delay=TIME@RATE"),
            ("delay=5@1%", "a time"),
            ("down=1s", "START+LENGTH"),
            ("seed=x", "integer"),
            ("noise=1%", "unknown kind"),
            ("drop=60%,corrupt=60%", "more than 100"),
        ] {
            let e = text.parse::<FaultConfig>().unwrap_err();
            assert!(e.to_string().contains(why), "{text}: {e}");
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_faults_and_rates_hold() {
        let c: FaultConfig = "drop=2%,corrupt=1%,dup=1%,seed=42".parse().unwrap();
        let run = |c: &FaultConfig| {
            let mut f = FaultInjector::new(c.clone());
            let fates: Vec<Fate> = (0..100_000).map(|_| f.fate(Duration::ZERO)).collect();
            (fates, f.stats())
        };
        let (a, sa) = run(&c);
        let (b, _) = run(&c);
        assert_eq!(a, b);
        assert_eq!(sa.frames, 100_000);
        // 2 % +- a generous margin.
        let dropped = sa.dropped_before + sa.dropped_after;
        assert!((1_500..2_500).contains(&dropped), "{sa:?}");
        assert!((700..1_300).contains(&sa.corrupted), "{sa:?}");
        assert!((700..1_300).contains(&sa.duplicated), "{sa:?}");
        assert_eq!(sa.lost(), dropped + sa.corrupted);
    }

    #[test]
    fn forced_fates_hit_exactly_their_frame_and_heal_ends_everything() {
        let mut f = FaultInjector::new("drop=0%".parse().unwrap());
        f.force(2, Fate::DropAfter);
        let fates: Vec<Fate> = (0..4).map(|_| f.fate(Duration::ZERO)).collect();
        assert_eq!(
            fates,
            [Fate::Deliver, Fate::Deliver, Fate::DropAfter, Fate::Deliver]
        );
        assert_eq!(f.stats().dropped_after, 1);
        f.pull_cable(Duration::from_secs(1), Duration::from_secs(1));
        assert_eq!(f.fate(Duration::from_millis(1500)), Fate::LinkDown);
        f.heal();
        assert_eq!(f.fate(Duration::from_millis(1500)), Fate::Deliver);
    }

    #[test]
    fn the_link_is_down_exactly_in_its_windows() {
        let c: FaultConfig = "down=1s+500ms,down=3s+1ms".parse().unwrap();
        let mut f = FaultInjector::new(c);
        let ms = Duration::from_millis;
        assert_eq!(f.fate(ms(999)), Fate::Deliver);
        assert_eq!(f.fate(ms(1000)), Fate::LinkDown);
        assert_eq!(f.fate(ms(1499)), Fate::LinkDown);
        assert_eq!(f.fate(ms(1500)), Fate::Deliver);
        assert_eq!(f.fate(ms(3000)), Fate::LinkDown);
        assert_eq!(f.fate(ms(3001)), Fate::Deliver);
        assert_eq!(f.stats().link_down, 3);
    }
}
