//! Snapshots: the whole state of an environment, to clone and restore, and to save as bytes.
//!
//! A [`Snapshot`] holds the options, the rules' state (world, generator, last applied action) and, with
//! `frame_stack > 1`, the stacked observation, so a restored environment continues exactly as the original
//! would: same observations, rewards, flags and infos.
//!
//! # Byte format (version 3, little-endian)
//! `"CSNP"`, `u16` version, `u32` payload length, payload, `u32` CRC-32 of the payload. The payload is: the
//! options (every [`Config`] field, in declaration order), the generator state (`4 × u64`), the last applied action (`u8`), the world
//! (chopper, fuel, return, lives, steps, status, then each entity list as a `u32` count and its boxes), and the
//! stacked observation (`u8` dtype tag, `u32` count, elements). Decoding checks the magic, the version, the
//! length, the checksum and every value's range, so truncated, corrupted or foreign bytes give an error,
//! never a panic or a wrong state. Bytes with a correct checksum are not trusted either: the options are
//! checked (memory budget included) and the frame stack's length computed from them before anything is
//! allocated, and every value is checked against what the rules can reach (`reachable.rs`), so a decoded
//! snapshot is always a state the game could be in.
//!
//! # Versions
//! - 3: `look` (`u8`: 0 auto, 1 art, 2 agent) follows `hud_style`.
//! - 2: no `look`. Still read, as `look = "art"`: such a snapshot was taken when every frame showed the art, so
//!   it decodes to exactly those frames (its frame stack included), as version 1 does for the HUD below.
//! - 2: `hud_style` (`u8`: 0 auto, 1 text, 2 gauge) follows `hud`.
//! - 1: no `hud_style`. Still read: such a snapshot was taken when every frame carried the text HUD, so it
//!   decodes with `hud_style = "text"`, which draws exactly those frames (its frame stack included); restoring
//!   it into an environment of another `hud_style` is refused naming the option, like any other option.

use crate::action::Action;
use crate::config::{BirdFuelCollision, Config, HudStyle, Look, ObsType};
use crate::consts::{ALIEN_SIZE, BIRD_SIZE, CHOPPER_SIZE, FUEL_TANK_SIZE, MISSILE_SIZE};
use crate::env::ChopperScape;
use crate::error::{Error, SnapshotError};
use crate::geometry::Rect;
use crate::obs_buffer::ObsData;
use crate::obs_pipeline::stacked_len;
use crate::reachable::{MAX_BIRDS, MAX_FUEL_TANKS, MAX_MISSILES, check_stacked, check_world};
use crate::rng::Rng;
use crate::rules::Game;
use crate::world::{Alien, Cause, Status, World};

/// The snapshot byte format's version, the one written. Versions 1 to this one are read; others are refused.
pub const SNAPSHOT_VERSION: u16 = 3;
/// The oldest version still read.
const OLDEST_VERSION: u16 = 1;
const MAGIC: &[u8; 4] = b"CSNP";

/// The whole state of a [`ChopperScape`] environment.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    game: Game,
    stacked: ObsData,
}

impl Snapshot {
    /// The options the snapshot was taken with.
    pub fn config(&self) -> &Config {
        self.game.config()
    }

    /// The world at the time of the snapshot.
    pub fn world(&self) -> &World {
        self.game.world()
    }

    /// Encodes the snapshot as bytes (see the module docs for the format).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut p = Writer(Vec::with_capacity(256));
        let c = self.game.config();
        p.u8(c.obs_type as u8);
        p.u32(c.obs_size.0);
        p.u32(c.obs_size.1);
        p.u32(c.frame_stack);
        p.u8(c.hud as u8);
        p.u8(c.hud_style as u8);
        p.u8(c.look as u8);
        p.u32(c.lives);
        p.u8(c.bird_fuel_collision as u8);
        p.f64(c.alien_prob);
        p.u32(c.frame_skip);
        p.f64(c.sticky_prob);
        p.f64(c.bird_prob);
        p.f64(c.fuel_prob);
        p.u32(c.max_fuel);
        p.u32(c.max_episode_steps.unwrap_or(0));
        for w in self.game.rng.state() {
            p.u64(w);
        }
        p.u8(self.game.prev_action as u8);
        let w = self.game.world();
        p.rect(&w.chopper);
        p.u32(w.fuel_left);
        p.i64(w.episode_return);
        p.u32(w.lives);
        p.u32(w.steps);
        p.u8(match w.status {
            Status::NotStarted => 0,
            Status::Running => 1,
            Status::Terminated(Cause::Bird) => 2,
            Status::Terminated(Cause::Fuel) => 3,
            Status::Truncated => 4,
        });
        p.rects(&w.birds);
        p.rects(&w.fuel_tanks);
        p.u32(w.aliens.len() as u32);
        for a in &w.aliens {
            p.rect(&a.body);
            p.u32(a.age);
        }
        p.rects(&w.missiles);
        match &self.stacked {
            ObsData::U8(v) => {
                p.u8(0);
                p.u32(v.len() as u32);
                p.0.extend_from_slice(v);
            }
            ObsData::F32(v) => {
                p.u8(1);
                p.u32(v.len() as u32);
                v.iter().for_each(|x| p.0.extend_from_slice(&x.to_le_bytes()));
            }
        }
        let payload = p.0;
        let mut out = Vec::with_capacity(payload.len() + 14);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&SNAPSHOT_VERSION.to_le_bytes());
        out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        out.extend_from_slice(&payload);
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        out
    }

    /// Decodes bytes written by [`Snapshot::to_bytes`].
    ///
    /// # Errors
    /// Foreign bytes, another format version, truncated bytes, a checksum mismatch, or any value out of range.
    pub fn from_bytes(bytes: &[u8]) -> Result<Snapshot, SnapshotError> {
        if bytes.len() < 4 || &bytes[..4] != MAGIC {
            return Err(SnapshotError::NotASnapshot);
        }
        let mut r = Reader { b: &bytes[4..] };
        let version = r.u16("version")?;
        if !(OLDEST_VERSION..=SNAPSHOT_VERSION).contains(&version) {
            return Err(SnapshotError::Version { found: version, supported: SNAPSHOT_VERSION });
        }
        let len = r.u32("payload length")? as usize;
        let payload = r.take(len, "payload")?;
        let crc = r.u32("checksum")?;
        if !r.b.is_empty() {
            return Err(SnapshotError::Corrupted(format!("{} unexpected bytes after the checksum", r.b.len())));
        }
        // Under `cargo fuzz` the checksum is not enforced, so the fuzzer reaches the field checks behind it.
        if !cfg!(fuzzing) && crc32fast::hash(payload) != crc {
            return Err(SnapshotError::Corrupted("checksum mismatch".into()));
        }
        let snap = decode_payload(&mut Reader { b: payload }, version)?;
        Ok(snap)
    }
}

impl ChopperScape {
    /// The whole state of this environment.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot { game: self.game().clone(), stacked: self.observer().stacked().clone() }
    }

    /// Restores a snapshot taken from an environment with the same options; the environment then continues
    /// exactly as the one the snapshot was taken from.
    ///
    /// # Errors
    /// [`SnapshotError::ConfigMismatch`] naming the options that differ; nothing changes then.
    pub fn restore(&mut self, snapshot: &Snapshot) -> Result<(), Error> {
        if snapshot.config() != self.config() {
            let differ = snapshot.config().differences(self.config()).join(", ");
            return Err(SnapshotError::ConfigMismatch(format!("{differ} (snapshot != environment)")).into());
        }
        let (game, observer) = self.parts_mut();
        game.clone_from(&snapshot.game);
        observer.set_stacked(snapshot.stacked.clone());
        Ok(())
    }

    /// A new environment in the state of the snapshot, with its options.
    ///
    /// # Errors
    /// [`crate::ConfigError::OutOfMemory`] when the system refuses the memory of the observation buffers (the
    /// decoder has checked the options, memory budget included).
    pub fn from_snapshot(snapshot: &Snapshot) -> Result<ChopperScape, Error> {
        let mut env = ChopperScape::new(snapshot.config().clone())?;
        env.restore(snapshot)?;
        Ok(env)
    }
}

fn decode_payload(r: &mut Reader<'_>, version: u16) -> Result<Snapshot, SnapshotError> {
    let bad = |what: &str| SnapshotError::Corrupted(what.to_string());
    let obs_type = *ObsType::ALL.get(r.u8("obs_type")? as usize).ok_or_else(|| bad("obs_type"))?;
    let obs_size = (r.u32("obs_size")?, r.u32("obs_size")?);
    let frame_stack = r.u32("frame_stack")?;
    let hud = match r.u8("hud")? {
        0 => false,
        1 => true,
        _ => return Err(bad("hud")),
    };
    let hud_style = if version >= 2 {
        *HudStyle::ALL.get(r.u8("hud_style")? as usize).ok_or_else(|| bad("hud_style"))?
    } else {
        HudStyle::Text
    };
    let look =
        if version >= 3 { *Look::ALL.get(r.u8("look")? as usize).ok_or_else(|| bad("look"))? } else { Look::Art };
    let lives = r.u32("lives")?;
    let bird_fuel_collision = match r.u8("bird_fuel_collision")? {
        0 => BirdFuelCollision::Pass,
        1 => BirdFuelCollision::Destroy,
        _ => return Err(bad("bird_fuel_collision")),
    };
    let config = Config {
        obs_type,
        obs_size,
        frame_stack,
        hud,
        hud_style,
        look,
        lives,
        bird_fuel_collision,
        alien_prob: r.f64("alien_prob")?,
        frame_skip: r.u32("frame_skip")?,
        sticky_prob: r.f64("sticky_prob")?,
        bird_prob: r.f64("bird_prob")?,
        fuel_prob: r.f64("fuel_prob")?,
        max_fuel: r.u32("max_fuel")?,
        max_episode_steps: Some(r.u32("max_episode_steps")?).filter(|&s| s != 0),
    };
    config.validate().map_err(|e| SnapshotError::Corrupted(format!("options: {e}")))?;
    let mut state = [0u64; 4];
    for w in &mut state {
        *w = r.u64("generator state")?;
    }
    let rng = Rng::from_state(state).ok_or_else(|| bad("all-zero generator state"))?;
    let prev_action = Action::try_from(r.u8("last action")? as i64).map_err(|_| bad("last action"))?;
    let chopper = r.rect(CHOPPER_SIZE, "chopper")?;
    let fuel_left = r.u32("fuel")?;
    let episode_return = r.i64("return")?;
    let lives_left = r.u32("lives left")?;
    let steps = r.u32("steps")?;
    let status = match r.u8("status")? {
        0 => Status::NotStarted,
        1 => Status::Running,
        2 => Status::Terminated(Cause::Bird),
        3 => Status::Terminated(Cause::Fuel),
        4 => Status::Truncated,
        _ => return Err(bad("status")),
    };
    let birds = r.rects(BIRD_SIZE, MAX_BIRDS, "birds")?;
    let fuel_tanks = r.rects(FUEL_TANK_SIZE, MAX_FUEL_TANKS, "fuel tanks")?;
    let n = r.count(12, MAX_BIRDS, "aliens")?;
    let mut aliens = Vec::with_capacity(n);
    for _ in 0..n {
        aliens.push(Alien { body: r.rect(ALIEN_SIZE, "alien")?, age: r.u32("alien age")? });
    }
    let missiles = r.rects(MISSILE_SIZE, MAX_MISSILES, "missiles")?;
    let world = World {
        chopper,
        birds,
        fuel_tanks,
        aliens,
        missiles,
        fuel_left,
        episode_return,
        lives: lives_left,
        steps,
        status,
    };
    check_world(&config, &world, prev_action).map_err(SnapshotError::Corrupted)?;

    // The frame stack's length follows from the options: checked before anything is allocated for it.
    let expected = stacked_len(&config);
    let dtype = r.u8("observation type")?;
    let f32s = matches!(config.obs_type, ObsType::RgbFloat | ObsType::Features);
    if dtype != u8::from(f32s) {
        return Err(bad("observation type does not match the options"));
    }
    let n = r.u32("stacked observation")? as usize;
    if n != expected {
        return Err(SnapshotError::Corrupted(format!(
            "stacked observation holds {n} values: the options give {expected}"
        )));
    }
    let stacked = if f32s {
        let bytes = r.take(n.checked_mul(4).ok_or_else(|| bad("stacked observation"))?, "stacked observation")?;
        ObsData::F32(bytes.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect())
    } else {
        ObsData::U8(r.take(n, "stacked observation")?.to_vec())
    };
    check_stacked(&config, status, &stacked).map_err(SnapshotError::Corrupted)?;
    let game = Game::from_parts(config, world, rng, prev_action);
    if !r.b.is_empty() {
        return Err(bad("trailing bytes in the payload"));
    }
    Ok(Snapshot { game, stacked })
}

struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn rect(&mut self, r: &Rect) {
        self.0.extend_from_slice(&r.x.to_le_bytes());
        self.0.extend_from_slice(&r.y.to_le_bytes());
    }
    fn rects(&mut self, rs: &[Rect]) {
        self.u32(rs.len() as u32);
        rs.iter().for_each(|r| self.rect(r));
    }
}

struct Reader<'a> {
    b: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], SnapshotError> {
        if self.b.len() < n {
            return Err(SnapshotError::Truncated(what));
        }
        let (head, tail) = self.b.split_at(n);
        self.b = tail;
        Ok(head)
    }
    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], SnapshotError> {
        Ok(self.take(N, what)?.try_into().expect("N bytes"))
    }
    fn u8(&mut self, what: &'static str) -> Result<u8, SnapshotError> {
        Ok(self.take(1, what)?[0])
    }
    fn u16(&mut self, what: &'static str) -> Result<u16, SnapshotError> {
        self.array(what).map(u16::from_le_bytes)
    }
    fn u32(&mut self, what: &'static str) -> Result<u32, SnapshotError> {
        self.array(what).map(u32::from_le_bytes)
    }
    fn u64(&mut self, what: &'static str) -> Result<u64, SnapshotError> {
        self.array(what).map(u64::from_le_bytes)
    }
    fn i64(&mut self, what: &'static str) -> Result<i64, SnapshotError> {
        self.array(what).map(i64::from_le_bytes)
    }
    fn f64(&mut self, what: &'static str) -> Result<f64, SnapshotError> {
        self.array(what).map(f64::from_le_bytes)
    }
    /// A count of items of `item_len` bytes each, refused when the rest of the bytes cannot hold them.
    /// At most `max` of them (what the rules can reach).
    fn count(&mut self, item_len: usize, max: usize, what: &'static str) -> Result<usize, SnapshotError> {
        let n = self.u32(what)? as usize;
        if n > max {
            return Err(SnapshotError::Corrupted(format!("{n} {what}: at most {max} can be on screen")));
        }
        if n.saturating_mul(item_len) > self.b.len() {
            return Err(SnapshotError::Truncated(what));
        }
        Ok(n)
    }
    /// A box of the given size; its position must lie in the flight band.
    fn rect(&mut self, size: (i32, i32), what: &'static str) -> Result<Rect, SnapshotError> {
        let x = i32::from_le_bytes(self.array(what)?);
        let y = i32::from_le_bytes(self.array(what)?);
        let r = Rect { x, y, w: size.0, h: size.1 };
        if r.in_band() {
            Ok(r)
        } else {
            Err(SnapshotError::Corrupted(format!("{what} at ({x}, {y}) is outside the flight band")))
        }
    }
    fn rects(&mut self, size: (i32, i32), max: usize, what: &'static str) -> Result<Vec<Rect>, SnapshotError> {
        let n = self.count(8, max, what)?;
        (0..n).map(|_| self.rect(size, what)).collect()
    }
}
