//! The samples accumulated while reading ([`Acc`]) and the composition of `/tf` transform
//! trees to their root frame.

use crate::data::{ros_cdr, Plane};
use std::collections::{BTreeMap, HashMap};

/// One marker's samples with nanosecond stamps.
pub(super) type Stamped = Vec<(i64, Option<[f64; 2]>)>;

/// One transform of a `/tf` tree: the child frame's pose in its parent frame.
struct Tf {
    ns: i64,
    parent: String,
    child: String,
    translation: [f64; 3],
    rotation: [f64; 4],
    /// From `/tf_static`: holds for the whole recording.
    fixed: bool,
}

/// Accumulates marker samples with nanosecond stamps, per channel (topic) and marker name,
/// and the transforms of `/tf` trees to compose at the end.
#[derive(Default)]
pub(super) struct Acc {
    index: HashMap<(String, String), usize>,
    /// Topic, marker name, samples; in the order markers were first seen.
    pub(super) series: Vec<(String, String, Stamped)>,
    tf: Vec<Tf>,
    /// The series after the one pushed to last.
    next: usize,
}

impl Acc {
    pub(super) fn push(&mut self, topic: &str, name: &str, ns: i64, p: Option<[f64; 2]>) {
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
    }

    pub(super) fn push_tf(&mut self, t: ros_cdr::TransformStamped, fixed: bool) {
        self.tf.push(Tf {
            ns: t.header.stamp.ns(),
            parent: t.header.frame_id,
            child: t.child_frame_id,
            translation: t.translation,
            rotation: t.rotation,
            fixed,
        });
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

/// Compose `/tf` transforms to their tree's root: at every stamp of a dynamic transform, every
/// frame's origin in the root frame. Static transforms hold for the whole recording. The samples
/// go to `acc` under the topic `/tf`; returns notes on the roots used.
pub(super) fn compose_tf(acc: &mut Acc, plane: Option<Plane>) -> Result<Vec<String>, String> {
    let tf = std::mem::take(&mut acc.tf);
    let mut current: BTreeMap<String, (String, [f64; 3], [f64; 4])> = BTreeMap::new();
    let mut dynamic: Vec<&Tf> = Vec::new();
    for t in &tf {
        if t.fixed {
            current.insert(
                t.child.clone(),
                (t.parent.clone(), t.translation, t.rotation),
            );
        } else {
            dynamic.push(t);
        }
    }
    dynamic.sort_by_key(|t| t.ns);
    let mut frames: BTreeMap<&str, ()> = BTreeMap::new();
    for t in &tf {
        frames.insert(&t.child, ());
    }
    let stamps = dynamic.chunk_by(|a, b| a.ns == b.ns).count();
    if stamps.saturating_mul(frames.len()) > TF_SAMPLE_LIMIT {
        return Err(format!(
            "a /tf tree of at most {TF_SAMPLE_LIMIT} frame samples, found {} frames at {stamps} stamps",
            frames.len()
        ));
    }
    // Each frame's root in the whole recording's tree: a frame is placed only once its chain
    // reaches that root, so its positions never switch frames when a parent arrives late.
    let mut parent_of: HashMap<&str, &str> = HashMap::new();
    for t in &tf {
        parent_of.insert(&t.child, &t.parent);
    }
    let depth_limit = frames.len() + 1;
    let root_of = |f: &str| -> Option<String> {
        let mut f = f;
        for _ in 0..=depth_limit {
            match parent_of.get(f) {
                Some(p) => f = p,
                None => return Some(f.to_string()),
            }
        }
        None
    };
    let final_root: HashMap<String, Option<String>> =
        frames.keys().map(|f| (f.to_string(), root_of(f))).collect();
    let mut roots: BTreeMap<String, usize> = BTreeMap::new();
    for group in dynamic.chunk_by(|a, b| a.ns == b.ns) {
        for t in group {
            current.insert(
                t.child.clone(),
                (t.parent.clone(), t.translation, t.rotation),
            );
        }
        let ns = group[0].ns;
        for child in current.keys() {
            let (mut frame, mut p) = (child.as_str(), [0.0; 3]);
            let mut depth = 0;
            while let Some((parent, tr, q)) = current.get(frame) {
                let r = rotate(*q, p);
                p = [r[0] + tr[0], r[1] + tr[1], r[2] + tr[2]];
                frame = parent;
                depth += 1;
                if depth > depth_limit {
                    return Err(format!("a /tf tree, found a cycle through frame {child:?}"));
                }
            }
            if final_root.get(child).and_then(|r| r.as_deref()) != Some(frame) {
                // The chain to the root is not complete yet at this stamp.
                continue;
            }
            if p.iter().all(|v| v.is_finite()) {
                *roots.entry(frame.to_string()).or_default() += 1;
                let xy = match plane {
                    Some(pl) => pl.project(p),
                    None => [p[0], p[1]],
                };
                acc.push("/tf", child, ns, Some(xy));
            } else {
                acc.push("/tf", child, ns, None);
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
