//! Structure-aware snapshots: a real state (arbitrary options, played with arbitrary actions) whose fields are
//! then edited arbitrarily and encoded with a correct checksum, so the decoder's value checks (not its
//! checksum) are what the fuzzer meets. A snapshot the decoder accepts must re-encode to its bytes, build an
//! environment, and step without panicking into states that encode and decode again (what the rules reach
//! from a reachable state is reachable).
#![no_main]
use arbitrary::Arbitrary;
use chopperscape::{ChopperScape, Config, Env, ObsType, Snapshot, Status};
use libfuzzer_sys::fuzz_target;

/// One edit of a decoded field.
#[derive(Arbitrary, Debug)]
enum Edit {
    ObsType(u8),
    ObsSize(u32, u32),
    FrameStack(u32),
    HudStyle(u8),
    Look(u8),
    Lives(u32),
    FrameSkip(u32),
    MaxFuel(u32),
    MaxEpisodeSteps(u32),
    Prob(u8, f64),
    Generator(u8, u64),
    LastAction(u8),
    Chopper(i32, i32),
    Fuel(u32),
    Return(i64),
    LivesLeft(u32),
    Steps(u32),
    Status(u8),
    Entity(u8, u16, i32, i32),
    AlienAge(u16, u32),
    Push(u8, i32, i32),
    Remove(u8, u16),
    StackValue(u32, u32),
    StackLen(u32),
}

#[derive(Arbitrary, Debug)]
struct Input {
    obs_type: u8,
    frame_stack: u8,
    hud_style: u8,
    lives: u8,
    aliens: bool,
    destroy: bool,
    seed: u64,
    actions: Vec<u8>,
    edits: Vec<Edit>,
    steps_after: Vec<u8>,
}

/// A snapshot's payload as fields, in format order (version 3: see crates/core/src/snapshot.rs).
#[derive(Clone, Debug)]
struct Fields {
    head: [u8; 1],
    obs_size: (u32, u32),
    frame_stack: u32,
    hud: u8,
    hud_style: u8,
    look: u8,
    lives: u32,
    bfc: u8,
    alien_prob: f64,
    frame_skip: u32,
    sticky_prob: f64,
    bird_prob: f64,
    fuel_prob: f64,
    max_fuel: u32,
    max_episode_steps: u32,
    rng: [u64; 4],
    last_action: u8,
    chopper: (i32, i32),
    fuel: u32,
    ret: i64,
    lives_left: u32,
    steps: u32,
    status: u8,
    lists: [Vec<(i32, i32)>; 2],
    aliens: Vec<(i32, i32, u32)>,
    missiles: Vec<(i32, i32)>,
    stack_tag: u8,
    stack: Vec<u8>,
}

struct R<'a>(&'a [u8]);
impl R<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let (h, t) = self.0.split_at(N);
        self.0 = t;
        h.try_into().unwrap()
    }
    fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn i32(&mut self) -> i32 {
        i32::from_le_bytes(self.take())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
    fn pairs(&mut self) -> Vec<(i32, i32)> {
        (0..self.u32()).map(|_| (self.i32(), self.i32())).collect()
    }
}

fn parse(bytes: &[u8]) -> Fields {
    let mut r = R(&bytes[10..bytes.len() - 4]);
    let mut f = Fields {
        head: [r.u8()],
        obs_size: (r.u32(), r.u32()),
        frame_stack: r.u32(),
        hud: r.u8(),
        hud_style: r.u8(),
        look: r.u8(),
        lives: r.u32(),
        bfc: r.u8(),
        alien_prob: r.f64(),
        frame_skip: r.u32(),
        sticky_prob: r.f64(),
        bird_prob: r.f64(),
        fuel_prob: r.f64(),
        max_fuel: r.u32(),
        max_episode_steps: r.u32(),
        rng: [r.u64(), r.u64(), r.u64(), r.u64()],
        last_action: r.u8(),
        chopper: (r.i32(), r.i32()),
        fuel: r.u32(),
        ret: i64::from_le_bytes(r.take()),
        lives_left: r.u32(),
        steps: r.u32(),
        status: r.u8(),
        lists: [Vec::new(), Vec::new()],
        aliens: Vec::new(),
        missiles: Vec::new(),
        stack_tag: 0,
        stack: Vec::new(),
    };
    f.lists = [r.pairs(), r.pairs()];
    f.aliens = (0..r.u32()).map(|_| (r.i32(), r.i32(), r.u32())).collect();
    f.missiles = r.pairs();
    f.stack_tag = r.u8();
    let n = r.u32() as usize * if f.stack_tag == 1 { 4 } else { 1 };
    f.stack = r.0[..n].to_vec();
    f
}

fn encode(f: &Fields, stack_len: Option<u32>) -> Vec<u8> {
    let mut p = Vec::new();
    let u32 = |p: &mut Vec<u8>, v: u32| p.extend_from_slice(&v.to_le_bytes());
    let i32 = |p: &mut Vec<u8>, v: i32| p.extend_from_slice(&v.to_le_bytes());
    p.push(f.head[0]);
    u32(&mut p, f.obs_size.0);
    u32(&mut p, f.obs_size.1);
    u32(&mut p, f.frame_stack);
    p.push(f.hud);
    p.push(f.hud_style);
    p.push(f.look);
    u32(&mut p, f.lives);
    p.push(f.bfc);
    p.extend_from_slice(&f.alien_prob.to_le_bytes());
    u32(&mut p, f.frame_skip);
    for x in [f.sticky_prob, f.bird_prob, f.fuel_prob] {
        p.extend_from_slice(&x.to_le_bytes());
    }
    u32(&mut p, f.max_fuel);
    u32(&mut p, f.max_episode_steps);
    f.rng.iter().for_each(|w| p.extend_from_slice(&w.to_le_bytes()));
    p.push(f.last_action);
    i32(&mut p, f.chopper.0);
    i32(&mut p, f.chopper.1);
    u32(&mut p, f.fuel);
    p.extend_from_slice(&f.ret.to_le_bytes());
    u32(&mut p, f.lives_left);
    u32(&mut p, f.steps);
    p.push(f.status);
    for list in &f.lists {
        u32(&mut p, list.len() as u32);
        for &(x, y) in list {
            i32(&mut p, x);
            i32(&mut p, y);
        }
    }
    u32(&mut p, f.aliens.len() as u32);
    for &(x, y, age) in &f.aliens {
        i32(&mut p, x);
        i32(&mut p, y);
        u32(&mut p, age);
    }
    u32(&mut p, f.missiles.len() as u32);
    for &(x, y) in &f.missiles {
        i32(&mut p, x);
        i32(&mut p, y);
    }
    p.push(f.stack_tag);
    let elem = if f.stack_tag == 1 { 4 } else { 1 };
    u32(&mut p, stack_len.unwrap_or((f.stack.len() / elem) as u32));
    p.extend_from_slice(&f.stack);
    let mut out = b"CSNP".to_vec();
    out.extend_from_slice(&chopperscape::SNAPSHOT_VERSION.to_le_bytes());
    out.extend_from_slice(&(p.len() as u32).to_le_bytes());
    out.extend_from_slice(&p);
    out.extend_from_slice(&crc32fast::hash(&p).to_le_bytes());
    out
}

fn apply(f: &mut Fields, e: &Edit, stack_len: &mut Option<u32>) {
    fn list(f: &mut Fields, which: u8) -> &mut Vec<(i32, i32)> {
        match which % 3 {
            0 => &mut f.lists[0],
            1 => &mut f.lists[1],
            _ => &mut f.missiles,
        }
    }
    match *e {
        Edit::ObsType(t) => f.head[0] = t % 5,
        Edit::ObsSize(h, w) => f.obs_size = (h, w),
        Edit::FrameStack(k) => f.frame_stack = k,
        Edit::HudStyle(v) => f.hud_style = v,
        Edit::Look(v) => f.look = v,
        Edit::Lives(l) => f.lives = l,
        Edit::FrameSkip(s) => f.frame_skip = s,
        Edit::MaxFuel(m) => f.max_fuel = m,
        Edit::MaxEpisodeSteps(m) => f.max_episode_steps = m,
        Edit::Prob(i, p) => *[&mut f.alien_prob, &mut f.sticky_prob, &mut f.bird_prob, &mut f.fuel_prob][i as usize % 4] = p,
        Edit::Generator(i, w) => f.rng[i as usize % 4] = w,
        Edit::LastAction(a) => f.last_action = a,
        Edit::Chopper(x, y) => f.chopper = (x, y),
        Edit::Fuel(v) => f.fuel = v,
        Edit::Return(v) => f.ret = v,
        Edit::LivesLeft(v) => f.lives_left = v,
        Edit::Steps(v) => f.steps = v,
        Edit::Status(s) => f.status = s,
        Edit::Entity(which, i, x, y) => {
            if let Some(e) = list(f, which).get_mut(i as usize) {
                *e = (x, y);
            }
        }
        Edit::AlienAge(i, age) => {
            if let Some(a) = f.aliens.get_mut(i as usize) {
                a.2 = age;
            }
        }
        Edit::Push(which, x, y) => {
            if which % 4 == 3 {
                f.aliens.push((x, y, (x as u32) % 200));
            } else {
                list(f, which).push((x, y));
            }
        }
        Edit::Remove(which, i) => {
            if which % 4 == 3 {
                if (i as usize) < f.aliens.len() {
                    f.aliens.remove(i as usize);
                }
            } else {
                let l = list(f, which);
                if (i as usize) < l.len() {
                    l.remove(i as usize);
                }
            }
        }
        Edit::StackValue(i, bits) => {
            if f.stack_tag == 1 {
                let n = f.stack.len() / 4;
                if n > 0 {
                    let at = (i as usize % n) * 4;
                    f.stack[at..at + 4].copy_from_slice(&bits.to_le_bytes());
                }
            } else if !f.stack.is_empty() {
                let n = f.stack.len();
                f.stack[i as usize % n] = bits as u8;
            }
        }
        Edit::StackLen(n) => *stack_len = Some(n),
    }
}

fuzz_target!(|input: Input| {
    let obs_type = ObsType::ALL[input.obs_type as usize % 4];
    let config = Config {
        obs_type,
        obs_size: (8 + u32::from(input.obs_type % 5), 8 + u32::from(input.obs_type % 7)),
        frame_stack: 1 + u32::from(input.frame_stack % 4),
        hud_style: chopperscape::HudStyle::ALL[input.hud_style as usize % 3],
        look: chopperscape::Look::ALL[input.hud_style as usize / 3 % 3],
        lives: 1 + u32::from(input.lives % 4),
        alien_prob: if input.aliens { 0.2 } else { 0.0 },
        bird_prob: 0.2,
        fuel_prob: 0.2,
        max_fuel: 200,
        bird_fuel_collision: if input.destroy {
            chopperscape::BirdFuelCollision::Destroy
        } else {
            chopperscape::BirdFuelCollision::Pass
        },
        max_episode_steps: Some(300),
        ..Config::default()
    };
    let mut env = ChopperScape::new(config).unwrap();
    if !input.actions.is_empty() {
        env.reset(Some(input.seed));
    }
    for &a in input.actions.iter().take(400) {
        if env.world().status != Status::Running {
            break;
        }
        env.step(i64::from(a % 5)).unwrap();
    }
    let own = env.snapshot().to_bytes();
    let mut fields = parse(&own);
    assert_eq!(encode(&fields, None), own, "the harness's encoder matches the format");
    let mut stack_len = None;
    for e in input.edits.iter().take(16) {
        apply(&mut fields, e, &mut stack_len);
    }
    let bytes = encode(&fields, stack_len);
    let Ok(snap) = Snapshot::from_bytes(&bytes) else { return };
    assert_eq!(snap.to_bytes(), bytes, "a decoded snapshot re-encodes to its bytes");
    let mut env = ChopperScape::from_snapshot(&snap).expect("a decoded snapshot builds an env");
    for &a in input.steps_after.iter().take(200) {
        if env.step(i64::from(a % 5)).is_err() {
            break;
        }
        let w = env.world();
        assert!(w.chopper.in_band());
        assert!(w.birds.iter().chain(&w.fuel_tanks).chain(&w.missiles).all(|r| r.in_band()));
        assert!(w.fuel_left <= env.config().max_fuel && w.lives <= env.config().lives);
        let again = Snapshot::from_bytes(&env.snapshot().to_bytes());
        assert!(again.is_ok(), "a state stepped from an accepted one is refused: {again:?}");
    }
});
