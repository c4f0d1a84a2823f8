//! Fuzz bytes to ABI arguments. Every draw consumes bytes from the front and returns zeros once
//! they run out, so any input is a valid sequence of draws. Numbers are biased toward the values
//! that break floating-point code: zeros of both signs, subnormals, the ends of the range,
//! infinities, NaN, numbers a hair inside or outside an interval, and axis-aligned or grazing
//! directions.

use glam::DVec3;
use macrofacet_ffi::{mf_frame, mf_vec3};

/// The fuzz input, read front to back.
pub struct Bytes<'a> {
    data: &'a [u8],
}

/// Values that break floating-point code.
pub const EDGE_VALUES: [f64; 30] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    2.0,
    3.0,
    -3.0,
    6.0,
    38.6,
    -38.6,
    40.0,
    1e-6,
    1e6,
    1e-16,
    1.0 - 1e-16,
    1.0 + 1e-15,
    1e-300,
    -1e-300,
    1e300,
    -1e300,
    5e-324,
    f64::MIN_POSITIVE,
    f64::EPSILON,
    f64::MAX,
    -f64::MAX,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    1e-50,
];

impl<'a> Bytes<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { data }
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        let n = N.min(self.data.len());
        out[..n].copy_from_slice(&self.data[..n]);
        self.data = &self.data[n..];
        out
    }

    pub fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }

    pub fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }

    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }

    pub fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }

    pub fn bool(&mut self) -> bool {
        self.u8() & 1 == 1
    }

    /// One of `items` (the first when the input has run out).
    pub fn choose<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.u8() as usize % items.len()]
    }

    /// A number of bytes for a string or a count: `0..=max`.
    pub fn below(&mut self, max: usize) -> usize {
        self.u16() as usize % (max + 1)
    }

    /// Uniform in `[0, 1)` with 53 bits.
    pub fn unit(&mut self) -> f64 {
        (self.u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A log-uniform magnitude in `[10^lo, 10^hi]`.
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        10f64.powf(lo + (hi - lo) * self.unit())
    }

    /// Any `f64`: an edge value, raw bits, or an ordinary number of any magnitude.
    pub fn float(&mut self) -> f64 {
        match self.u8() % 4 {
            0 => self.choose(&EDGE_VALUES),
            1 => f64::from_bits(self.u64()),
            2 => (2.0 * self.unit() - 1.0) * 10.0,
            _ => {
                let sign = if self.bool() { -1.0 } else { 1.0 };
                sign * self.log_uniform(-320.0, 308.0)
            }
        }
    }

    /// A positive number, mostly inside `[10^lo, 10^hi]` (the domain a parameter accepts),
    /// sometimes just outside or anywhere ([`Self::float`]).
    pub fn positive(&mut self, lo: f64, hi: f64) -> f64 {
        match self.u8() % 16 {
            0 => self.float(),
            1 => 10f64.powf(lo) * (1.0 - 1e-12),
            2 => 10f64.powf(hi) * (1.0 + 1e-12),
            3 => 10f64.powf(lo),
            4 => 10f64.powf(hi),
            _ => self.log_uniform(lo, hi),
        }
    }

    /// A random number for a sampling call: mostly in `[0, 1)`, sometimes its ends or outside.
    pub fn uniform_arg(&mut self) -> f64 {
        match self.u8() % 16 {
            0 => self.float(),
            1 => 0.0,
            2 => 1.0 - f64::EPSILON / 2.0,
            3 => 1.0,
            4 => 5e-324,
            _ => self.unit(),
        }
    }

    /// A segment length: mostly `[0, 10 scale]`, sometimes 0, `+inf`, huge, negative or NaN.
    pub fn length(&mut self, scale: f64) -> f64 {
        match self.u8() % 10 {
            0 => f64::INFINITY,
            1 => 0.0,
            2 => self.float(),
            3 => scale * self.log_uniform(-12.0, 12.0),
            _ => 10.0 * scale * self.unit(),
        }
    }

    /// A signed distance: mostly within `±8 scale` of the mean surface, sometimes far or odd.
    pub fn signed_distance(&mut self, scale: f64) -> f64 {
        match self.u8() % 8 {
            0 => self.float(),
            1 => scale * self.choose(&EDGE_VALUES),
            _ => scale * (16.0 * self.unit() - 8.0),
        }
    }

    /// A uniform unit vector.
    pub fn sphere(&mut self) -> DVec3 {
        let z = 1.0 - 2.0 * self.unit();
        let phi = 2.0 * std::f64::consts::PI * self.unit();
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }

    /// A direction argument: mostly unit (exactly, or within the accepted 1e-6), sometimes
    /// axis-aligned, grazing to `normal`, or not a direction at all.
    pub fn direction(&mut self, normal: DVec3) -> DVec3 {
        match self.u8() % 12 {
            0 => DVec3::new(self.float(), self.float(), self.float()),
            1 => self.choose(&[DVec3::X, DVec3::Y, DVec3::Z, -DVec3::X, -DVec3::Y, -DVec3::Z]),
            2 => {
                // Grazing: orthogonal to the normal up to a tiny tilt.
                let n = normal.try_normalize().unwrap_or(DVec3::Z);
                let t = n.any_orthonormal_vector();
                let tilt = self.choose(&[0.0, 1e-300, -1e-300, 1e-16, -1e-16, 1e-8, -1e-8]);
                (t + n * tilt).normalize()
            }
            3 => self.sphere() * (1.0 + 2e-6 * (self.unit() - 0.5)), // at the 1e-6 tolerance
            4 => self.sphere() * (1.0 + 1e-3 * (self.unit() - 0.5)), // clearly not unit
            _ => self.sphere(),
        }
    }

    /// A frame: mostly a unit normal with an arbitrary tangent, sometimes extreme lengths,
    /// a zero or parallel tangent, or non-finite components.
    pub fn frame(&mut self) -> mf_frame {
        let normal = match self.u8() % 8 {
            0 => DVec3::new(self.float(), self.float(), self.float()),
            1 => self.sphere() * self.choose(&[5e-324, 1e-300, 1e-159, 1e200, 1e300, f64::MAX]),
            2 => DVec3::Z,
            _ => self.sphere(),
        };
        let tangent = match self.u8() % 8 {
            0 => DVec3::new(self.float(), self.float(), self.float()),
            1 => DVec3::ZERO,
            2 => normal,
            3 => DVec3::X,
            _ => self.sphere(),
        };
        mf_frame { normal: vec3(normal), tangent: vec3(tangent) }
    }

    /// `n` random numbers for a phase sample.
    pub fn uniforms<const N: usize>(&mut self) -> [f64; N] {
        std::array::from_fn(|_| self.uniform_arg())
    }

    /// A string of up to `max` bytes, mostly printable, sometimes any bytes (invalid UTF-8); no
    /// interior NUL (the C strings end at the first one).
    pub fn string(&mut self, max: usize) -> Vec<u8> {
        let n = self.below(max);
        let printable = self.u8() % 4 != 0;
        (0..n)
            .map(|_| {
                let b = self.u8();
                if printable {
                    b' ' + b % 95
                } else {
                    b.max(1)
                }
            })
            .collect()
    }
}

pub fn vec3(v: DVec3) -> mf_vec3 {
    mf_vec3 { x: v.x, y: v.y, z: v.z }
}

pub fn dvec3(v: mf_vec3) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}
