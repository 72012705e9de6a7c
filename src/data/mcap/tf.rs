//! The samples accumulated while reading ([`Acc`]) and the composition of `/tf` transform
//! trees to their root frame.

use super::decode::Failed;
use crate::data::{ros_cdr, Budget, DataError, Plane, Resource};
use std::collections::{BTreeMap, HashMap};

/// One marker's samples with nanosecond stamps.
pub(super) type Stamped = Vec<(i64, Option<[f64; 2]>)>;

/// One transform of a `/tf` tree: the child frame's pose in its parent frame.
struct Tf {
    ns: i64,
    /// The frames, by their number in [`Acc`]'s `frames` (names are kept once: a transform
    /// then takes 80 bytes, so the transforms a file's decoded-bytes budget allows, at 76
    /// bytes of CDR each at least, fit in memory).
    parent: u32,
    child: u32,
    translation: [f64; 3],
    rotation: [f64; 4],
    /// From `/tf_static`: holds for the whole recording.
    fixed: bool,
}

/// Accumulates marker samples with nanosecond stamps, per channel (topic) and marker name,
/// and the transforms of `/tf` trees to compose at the end; holds the file's budget, which the
/// series (and, by the decoders, the samples) are charged to.
pub(super) struct Acc {
    index: HashMap<(String, String), usize>,
    /// Topic, marker name, samples; in the order markers were first seen.
    pub(super) series: Vec<(String, String, Stamped)>,
    tf: Vec<Tf>,
    /// The frame names of the transforms, each once, and their numbers.
    frames: Vec<String>,
    frame_ids: HashMap<String, u32>,
    /// The series after the one pushed to last.
    next: usize,
    /// The input file's budget.
    pub(super) budget: Budget,
    /// The most points a `PointsAnnotation` on each topic has held (their series exist).
    pub(super) widest: HashMap<String, usize>,
}

impl Acc {
    /// An empty accumulator charging `budget`.
    pub(super) fn new(budget: Budget) -> Self {
        Acc {
            index: HashMap::new(),
            series: Vec::new(),
            tf: Vec::new(),
            frames: Vec::new(),
            frame_ids: HashMap::new(),
            next: 0,
            budget,
            widest: HashMap::new(),
        }
    }

    /// Add a sample (its position charged by the caller); a new marker's series is charged
    /// here, before it is created.
    pub(super) fn push(
        &mut self,
        topic: &str,
        name: &str,
        ns: i64,
        p: Option<[f64; 2]>,
    ) -> Result<(), DataError> {
        // Markers come in the same order in every frame: try the one after the last first, so
        // the usual sample needs no key (no allocation, no hash).
        let guess = self.next % self.series.len().max(1);
        let k = match self.series.get(guess) {
            Some((t, n, _)) if t == topic && n == name => guess,
            _ => {
                let key = (topic.to_string(), name.to_string());
                match self.index.get(&key) {
                    Some(&k) => k,
                    None => {
                        self.budget.charge(Resource::Series, 1)?;
                        self.index.insert(key, self.series.len());
                        self.series
                            .push((topic.to_string(), name.to_string(), Vec::new()));
                        self.series.len() - 1
                    }
                }
            }
        };
        self.series[k].2.push((ns, p));
        self.next = k + 1;
        Ok(())
    }

    /// Refuse the file now if `n` more of `r` would go over its limit, without spending them
    /// (they are charged as they are spent): for a decoder about to allocate for them.
    pub(super) fn afford(&mut self, r: Resource, n: u64) -> Result<(), DataError> {
        if n > self.budget.remaining(r) {
            // Over the limit: the charge fails, spends nothing, and words the error.
            self.budget.charge(r, n)?;
        }
        Ok(())
    }

    /// Keep a transform to compose at the end.
    pub(super) fn push_tf(&mut self, t: ros_cdr::TransformStamped, fixed: bool) {
        // Child first: frames are numbered as the composition always numbered them.
        let child = self.frame(t.child_frame_id);
        let parent = self.frame(t.header.frame_id);
        self.tf.push(Tf {
            ns: t.header.stamp.ns(),
            parent,
            child,
            translation: t.translation,
            rotation: t.rotation,
            fixed,
        });
    }

    /// The number of the frame `name`, given it if new. Frames are at most one per transform,
    /// and a transform takes 76 bytes of the decoded-bytes budget at least, so u32 holds them.
    fn frame(&mut self, name: String) -> u32 {
        if let Some(&k) = self.frame_ids.get(&name) {
            return k;
        }
        let k = self.frames.len() as u32;
        self.frames.push(name.clone());
        self.frame_ids.insert(name, k);
        k
    }

    pub(super) fn is_empty(&self) -> bool {
        self.series.is_empty() && self.tf.is_empty()
    }
}

/// Rotate `v` by the quaternion `q` (x, y, z, w; normalised here).
fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if !(n.is_finite() && n > 0.0) {
        return v;
    }
    let (x, y, z, w) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    // v' = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    let c = [
        y * v[2] - z * v[1],
        z * v[0] - x * v[2],
        x * v[1] - y * v[0],
    ];
    let cc = [
        y * c[2] - z * c[1],
        z * c[0] - x * c[2],
        x * c[1] - y * c[0],
    ];
    [
        v[0] + 2.0 * (w * c[0] + cc[0]),
        v[1] + 2.0 * (w * c[1] + cc[1]),
        v[2] + 2.0 * (w * c[2] + cc[2]),
    ]
}

/// The most samples a `/tf` tree may expand into (frames times distinct stamps).
pub const TF_SAMPLE_LIMIT: usize = 20_000_000;

/// The identity rotation (x, y, z, w).
const IDENTITY: [f64; 4] = [0.0, 0.0, 0.0, 1.0];

/// `q` normalised; the identity when it has no direction (zero or not finite), as [`rotate`]
/// treats it.
fn unit(q: [f64; 4]) -> [f64; 4] {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    if n.is_finite() && n > 0.0 {
        [q[0] / n, q[1] / n, q[2] / n, q[3] / n]
    } else {
        IDENTITY
    }
}

/// The Hamilton product `a b` (x, y, z, w): rotating by `b`, then by `a`.
fn mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let ([ax, ay, az, aw], [bx, by, bz, bw]) = (a, b);
    [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]
}

/// A frame's transform to its parent: the parent, translation and rotation.
type Link = (usize, [f64; 3], [f64; 4]);

/// A frame's pose in its tree's root at one stamp: rotation, origin, and the root.
#[derive(Clone, Copy)]
struct Composed {
    q: [f64; 4],
    t: [f64; 3],
    root: usize,
}

/// Compose `/tf` transforms to their tree's root: at every stamp of a dynamic transform, every
/// frame's origin in the root frame. Static transforms hold for the whole recording. The samples
/// go to `acc` under the topic `/tf`; returns notes on the roots used.
///
/// Each frame's pose in the root is composed once per stamp from its parent's (memoised), so a
/// stamp costs one step per frame whatever the depth of the chains; the steps are charged to
/// the budget as `TfWork`, the samples as `Samples`.
pub(super) fn compose_tf(acc: &mut Acc, plane: Option<Plane>) -> Result<Vec<String>, Failed> {
    let tf = std::mem::take(&mut acc.tf);
    // Frames by number (given as the transforms were read): every child and parent named.
    let frames = std::mem::take(&mut acc.frames);
    acc.frame_ids = HashMap::new();
    let names: Vec<&str> = frames.iter().map(String::as_str).collect();
    let links: Vec<(usize, usize)> = tf
        .iter()
        .map(|t| (t.child as usize, t.parent as usize))
        .collect();
    let n = names.len();
    // Each frame's transform to its parent now: the static ones first.
    let mut current: Vec<Option<Link>> = vec![None; n];
    let mut dynamic: Vec<(&Tf, (usize, usize))> = Vec::new();
    for (t, &(c, p)) in tf.iter().zip(&links) {
        if t.fixed {
            current[c] = Some((p, t.translation, t.rotation));
        } else {
            dynamic.push((t, (c, p)));
        }
    }
    dynamic.sort_by_key(|(t, _)| t.ns);
    // The children, in name order (the order their samples are pushed at each stamp).
    let mut children: Vec<usize> = links.iter().map(|&(c, _)| c).collect();
    children.sort_unstable_by_key(|&c| names[c]);
    children.dedup();
    let stamps = dynamic.chunk_by(|a, b| a.0.ns == b.0.ns).count();
    if stamps.saturating_mul(children.len()) > TF_SAMPLE_LIMIT {
        return Err(format!(
            "a /tf tree of at most {TF_SAMPLE_LIMIT} frame samples, found {} frames at {stamps} stamps",
            children.len()
        )
        .into());
    }
    // Each frame's root in the whole recording's tree: a frame is placed only once its chain
    // reaches that root, so its positions never switch frames when a parent arrives late.
    let mut final_parent: Vec<Option<usize>> = vec![None; n];
    for &(c, p) in &links {
        final_parent[c] = Some(p);
    }
    let final_root = roots_of(&final_parent);
    let mut roots: BTreeMap<&str, usize> = BTreeMap::new();
    // The poses composed at the current stamp (`at[f]` is the stamp's number when `pose[f]`
    // holds it), and the frames on the chain being walked.
    let mut pose = vec![
        Composed {
            q: IDENTITY,
            t: [0.0; 3],
            root: 0
        };
        n
    ];
    let mut at = vec![usize::MAX; n];
    // The walk each frame was last on (a frame met twice on one walk closes a cycle).
    let mut walking = vec![0u64; n];
    let mut walks = 0u64;
    let mut chain: Vec<usize> = Vec::new();
    for (stamp, group) in dynamic.chunk_by(|a, b| a.0.ns == b.0.ns).enumerate() {
        for &(t, (c, p)) in group {
            current[c] = Some((p, t.translation, t.rotation));
        }
        let ns = group[0].0.ns;
        for &child in &children {
            if current[child].is_none() {
                continue;
            }
            // Up the chain to a frame composed at this stamp, or the root.
            let mut f = child;
            chain.clear();
            walks += 1;
            let base = loop {
                if at[f] == stamp {
                    break pose[f];
                }
                let Some((parent, _, _)) = current[f] else {
                    break Composed {
                        q: IDENTITY,
                        t: [0.0; 3],
                        root: f,
                    };
                };
                if walking[f] == walks {
                    return Err(format!(
                        "a /tf tree, found a cycle through frame {:?}",
                        names[child]
                    )
                    .into());
                }
                walking[f] = walks;
                chain.push(f);
                f = parent;
            };
            acc.budget.charge(Resource::TfWork, chain.len() as u64)?;
            // Down again, composing each frame's pose from its parent's.
            let mut up = base;
            for &g in chain.iter().rev() {
                let (_, tr, q) = current[g].expect("a frame on the chain has a parent");
                let r = rotate(up.q, tr);
                up = Composed {
                    q: unit(mul(up.q, unit(q))),
                    t: [up.t[0] + r[0], up.t[1] + r[1], up.t[2] + r[2]],
                    root: up.root,
                };
                pose[g] = up;
                at[g] = stamp;
            }
            let Composed { t: p, root, .. } = pose[child];
            if final_root[child] != Some(root) {
                // The chain to the root is not complete yet at this stamp.
                continue;
            }
            acc.budget.charge(Resource::Samples, 1)?;
            if p.iter().all(|v| v.is_finite()) {
                *roots.entry(names[root]).or_default() += 1;
                let xy = match plane {
                    Some(pl) => pl.project(p),
                    None => [p[0], p[1]],
                };
                acc.push("/tf", names[child], ns, Some(xy))?;
            } else {
                acc.push("/tf", names[child], ns, None)?;
            }
        }
    }
    let mut notes = Vec::new();
    if !tf.is_empty() {
        let statics = tf.iter().filter(|t| t.fixed).count();
        notes.push(format!(
            "/tf: {} transform(s) ({statics} static, held for the whole recording) composed to the root frame{} {} at {stamps} stamp(s)",
            tf.len(),
            if roots.len() == 1 { "" } else { "s" },
            roots.keys().map(|r| format!("{r:?}")).collect::<Vec<_>>().join(", ")
        ));
    }
    Ok(notes)
}

/// Each frame's root given each frame's parent (`None` for a frame on or under a cycle), in
/// one pass: each frame is walked once, later walks stop at a frame already settled.
fn roots_of(parent: &[Option<usize>]) -> Vec<Option<usize>> {
    const UNKNOWN: u8 = 0;
    const WALKING: u8 = 1;
    const SETTLED: u8 = 2;
    let mut state = vec![UNKNOWN; parent.len()];
    let mut root = vec![None; parent.len()];
    let mut path = Vec::new();
    for start in 0..parent.len() {
        let mut f = start;
        path.clear();
        let found = loop {
            match state[f] {
                SETTLED => break root[f],
                // Back on this walk's own path: a cycle.
                WALKING => break None,
                _ => {}
            }
            state[f] = WALKING;
            path.push(f);
            match parent[f] {
                Some(p) => f = p,
                None => break Some(f),
            }
        };
        for &g in &path {
            state[g] = SETTLED;
            root[g] = found;
        }
    }
    root
}
