//! The few ROS 2 messages marker recordings use, decoded from CDR (XCDR1, either byte order)
//! with every length checked against the bytes left before anything is allocated.
//!
//! The `cdr` crate sizes a string's buffer from its length field before checking it against
//! the input, so a 312-byte message could ask for 4 GB; these messages are small and fixed, so
//! they are read here directly.

/// A ROS 2 time stamp (`builtin_interfaces/msg/Time`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RosTime {
    pub sec: i32,
    pub nanosec: u32,
}

impl RosTime {
    /// Nanoseconds since the epoch (cannot overflow: |sec| < 2^31).
    pub fn ns(self) -> i64 {
        self.sec as i64 * 1_000_000_000 + self.nanosec as i64
    }
}

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Header {
    pub stamp: RosTime,
    pub frame_id: String,
}

/// `geometry_msgs/msg/TransformStamped`: the child frame's pose in the parent (header) frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TransformStamped {
    pub header: Header,
    pub child_frame_id: String,
    pub translation: [f64; 3],
    /// Quaternion x, y, z, w.
    pub rotation: [f64; 4],
}

/// A CDR body reader: alignment counts from the end of the 4-byte encapsulation header.
struct Cdr<'a> {
    body: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> Cdr<'a> {
    fn new(data: &'a [u8]) -> Result<Self, String> {
        let Some((head, body)) = data.split_first_chunk::<4>() else {
            return Err(format!(
                "a 4-byte CDR encapsulation header, found {} byte(s)",
                data.len()
            ));
        };
        let little = match head[1] {
            0 | 2 => false,
            1 | 3 => true,
            k => return Err(format!("CDR encapsulation kind 0..3, found {k}")),
        };
        Ok(Cdr {
            body,
            pos: 0,
            little,
        })
    }

    fn take(&mut self, n: usize, align: usize, what: &str) -> Result<&'a [u8], String> {
        let start = self.pos.next_multiple_of(align);
        let end = start
            .checked_add(n)
            .filter(|&e| e <= self.body.len())
            .ok_or_else(|| {
                format!(
                    "{what}: {n} byte(s) at offset {start}, but the message body has {}",
                    self.body.len()
                )
            })?;
        self.pos = end;
        Ok(&self.body[start..end])
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b: [u8; 4] = self.take(4, 4, what)?.try_into().expect("4 bytes");
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn f64(&mut self, what: &str) -> Result<f64, String> {
        let b: [u8; 8] = self.take(8, 8, what)?.try_into().expect("8 bytes");
        Ok(if self.little {
            f64::from_le_bytes(b)
        } else {
            f64::from_be_bytes(b)
        })
    }

    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        let raw = self.take(n, 1, what)?;
        let raw = raw.strip_suffix(&[0]).unwrap_or(raw);
        String::from_utf8(raw.to_vec()).map_err(|_| format!("{what}: UTF-8 text"))
    }

    fn time(&mut self) -> Result<RosTime, String> {
        Ok(RosTime {
            sec: self.u32("header.stamp.sec")? as i32,
            nanosec: self.u32("header.stamp.nanosec")?,
        })
    }

    fn header(&mut self) -> Result<Header, String> {
        Ok(Header {
            stamp: self.time()?,
            frame_id: self.string("header.frame_id")?,
        })
    }

    fn vec3(&mut self, what: &str) -> Result<[f64; 3], String> {
        Ok([self.f64(what)?, self.f64(what)?, self.f64(what)?])
    }

    fn quat(&mut self, what: &str) -> Result<[f64; 4], String> {
        Ok([
            self.f64(what)?,
            self.f64(what)?,
            self.f64(what)?,
            self.f64(what)?,
        ])
    }

    fn transform(&mut self) -> Result<TransformStamped, String> {
        Ok(TransformStamped {
            header: self.header()?,
            child_frame_id: self.string("child_frame_id")?,
            translation: self.vec3("transform.translation")?,
            rotation: self.quat("transform.rotation")?,
        })
    }
}

/// `geometry_msgs/msg/PointStamped` or `PoseStamped` (the pose's position): header and point.
pub(crate) fn point_stamped(data: &[u8], pose: bool) -> Result<(Header, [f64; 3]), String> {
    let mut c = Cdr::new(data)?;
    let h = c.header()?;
    let p = c.vec3(if pose { "pose.position" } else { "point" })?;
    if pose {
        c.quat("pose.orientation")?;
    }
    Ok((h, p))
}

/// `geometry_msgs/msg/TransformStamped`.
pub(crate) fn transform_stamped(data: &[u8]) -> Result<TransformStamped, String> {
    Cdr::new(data)?.transform()
}

/// `tf2_msgs/msg/TFMessage`: a sequence of transforms.
pub(crate) fn tf_message(data: &[u8]) -> Result<Vec<TransformStamped>, String> {
    let mut c = Cdr::new(data)?;
    let n = c.u32("transforms (sequence length)")? as usize;
    // Each transform takes at least 72 bytes: the length cannot ask for more than the body holds.
    if n > c.body.len() / 72 {
        return Err(format!(
            "transforms: a sequence length the body can hold (at most {}), found {n}",
            c.body.len() / 72
        ));
    }
    (0..n).map(|_| c.transform()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_huge_string_length_is_an_error_not_an_allocation() {
        let mut m = vec![0, 1, 0, 0];
        m.extend_from_slice(&7i32.to_le_bytes());
        m.extend_from_slice(&8u32.to_le_bytes());
        m.extend_from_slice(&u32::MAX.to_le_bytes());
        m.extend_from_slice(b"rail\0");
        let e = point_stamped(&m, false).unwrap_err();
        assert!(e.contains("header.frame_id"), "{e}");
    }

    #[test]
    fn big_and_little_endian_agree() {
        let mut le = vec![0, 1, 0, 0];
        let mut be = vec![0, 0, 0, 0];
        for (m, w) in [(&mut le, true), (&mut be, false)] {
            let u = |v: u32| if w { v.to_le_bytes() } else { v.to_be_bytes() };
            let f = |v: f64| if w { v.to_le_bytes() } else { v.to_be_bytes() };
            m.extend_from_slice(&u(3));
            m.extend_from_slice(&u(5));
            m.extend_from_slice(&u(2));
            m.extend_from_slice(b"a\0");
            m.extend_from_slice(&[0, 0]); // pad to 8 (body offset 14 -> 16)
            for v in [1.5, -2.0, 0.25] {
                m.extend_from_slice(&f(v));
            }
        }
        let a = point_stamped(&le, false).unwrap();
        assert_eq!(a, point_stamped(&be, false).unwrap());
        assert_eq!(a.0.stamp.ns(), 3_000_000_005);
        assert_eq!(a.0.frame_id, "a");
        assert_eq!(a.1, [1.5, -2.0, 0.25]);
    }
}
