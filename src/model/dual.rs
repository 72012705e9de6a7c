//! The dual numbers the fit differentiates a run with: a value and N derivatives, the
//! derivatives always stored.
//!
//! num-dual's `DualSVec64` keeps its derivative part in an `Option` (to skip constants);
//! every operation then matches on it, and in the integrator's arithmetic that measured 2.7x
//! the cost of a plain array (a micro-benchmark of the integrator's kind of expression, 6 derivatives). This type is
//! num-dual's `DualVec` with the `Option` taken out: the operations, the chain rules and the
//! trait implementations are num-dual's own (its exported `impl_dual!` and
//! `impl_first_derivatives!` macros), so the numbers agree with `DualSVec64` bit for bit
//! wherever a derivative is finite.

use nalgebra::allocator::Allocator;
use nalgebra::{Const, DefaultAllocator, Dim, OVector, U1};
use num_dual::{
    chain_rule, first, forward_binop, impl_add_sub_rem, impl_assign_ops, impl_comparisons,
    impl_derivatives, impl_dual, impl_dual_struct, impl_first_derivatives, impl_float_const,
    impl_from_f, impl_from_primitive, impl_inv, impl_iterator, impl_neg, impl_num, impl_scalar_op,
    impl_signed, impl_zero_one, second, third, zeroth, DualNum, DualNumFloat, DualStruct,
};
use num_traits::{Float, FloatConst, FromPrimitive, Inv, Num, One, Signed, Zero};
use std::fmt;
use std::iter::{Product, Sum};
use std::marker::PhantomData;
use std::ops::{
    Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Rem, RemAssign, Sub, SubAssign,
};

/// A dual number with a value and a derivative vector of dimension `D`, always stored.
#[derive(Clone, Debug)]
pub struct DenseDual<T: DualNum<F>, F, D: Dim>
where
    DefaultAllocator: Allocator<D>,
{
    /// The value.
    pub re: T,
    /// The derivatives.
    pub eps: OVector<T, D>,
    f: PhantomData<F>,
}

impl<T: DualNum<F> + Copy, F: Copy, const N: usize> Copy for DenseDual<T, F, Const<N>> {}

/// `N` derivatives of an `f64`: what the fit's Jacobian runs in.
pub type Dual<const N: usize> = DenseDual<f64, f64, Const<N>>;

impl<T: DualNum<F>, F, D: Dim> DenseDual<T, F, D>
where
    DefaultAllocator: Allocator<D>,
{
    /// A dual number from its value and derivatives.
    #[inline]
    pub fn new(re: T, eps: OVector<T, D>) -> Self {
        Self {
            re,
            eps,
            f: PhantomData,
        }
    }

    /// A constant: every derivative zero. Only fixed sizes know their length here, and only
    /// they are used ([`Dual`]); a dynamic size gets no derivatives.
    #[inline]
    pub fn from_re(re: T) -> Self {
        let d = D::from_usize(D::try_to_usize().unwrap_or(0));
        Self::new(re, OVector::from_element_generic(d, U1, T::zero()))
    }
}

impl<const N: usize> Dual<N> {
    /// The value `re` seeded as variable `index` (derivative one there, zero elsewhere; no
    /// seed when `index >= N`).
    #[inline]
    pub fn variable(re: f64, index: usize) -> Self {
        let mut d = Self::from_re(re);
        if index < N {
            d.eps[index] = 1.0;
        }
        d
    }
}

/* chain rule */
impl<T: DualNum<F>, F: Float, D: Dim> DenseDual<T, F, D>
where
    DefaultAllocator: Allocator<D>,
{
    /// f(x) from f0 = f(re) and f1 = f'(re). Where f' is infinite (a square root at zero)
    /// a zero derivative stays zero, as num-dual's absent derivative does, not NaN.
    #[inline]
    fn chain_rule(&self, f0: T, f1: T) -> Self {
        if f1.re().is_finite() {
            Self::new(f0, &self.eps * f1)
        } else {
            Self::new(
                f0,
                self.eps.map(|e| {
                    if e.is_zero() {
                        T::zero()
                    } else {
                        e * f1.clone()
                    }
                }),
            )
        }
    }
}

/* product rule */
impl<T: DualNum<F>, F: Float, D: Dim> Mul<&DenseDual<T, F, D>> for &DenseDual<T, F, D>
where
    DefaultAllocator: Allocator<D>,
{
    type Output = DenseDual<T, F, D>;
    #[inline]
    fn mul(self, other: &DenseDual<T, F, D>) -> Self::Output {
        DenseDual::new(
            self.re.clone() * other.re.clone(),
            &self.eps * other.re.clone() + &other.eps * self.re.clone(),
        )
    }
}

/* quotient rule */
impl<T: DualNum<F>, F: Float, D: Dim> Div<&DenseDual<T, F, D>> for &DenseDual<T, F, D>
where
    DefaultAllocator: Allocator<D>,
{
    type Output = DenseDual<T, F, D>;
    #[inline]
    fn div(self, other: &DenseDual<T, F, D>) -> DenseDual<T, F, D> {
        let inv = other.re.recip();
        DenseDual::new(
            self.re.clone() * inv.clone(),
            (&self.eps * other.re.clone() - &other.eps * self.re.clone()) * inv.clone() * inv,
        )
    }
}

impl<T: DualNum<F>, F, D: Dim> fmt::Display for DenseDual<T, F, D>
where
    DefaultAllocator: Allocator<D>,
{
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{} + {}ε", self.re, self.eps)
    }
}

impl_first_derivatives!(DenseDual, [eps], [D], [D]);
impl_dual!(DenseDual, [eps], [D], [D]);

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::{Derivative, DualSVec64};

    fn both(v: f64, i: usize) -> (Dual<3>, DualSVec64<3>) {
        (
            Dual::<3>::variable(v, i),
            DualSVec64::<3>::new(v, Derivative::derivative_generic(Const::<3>, U1, i)),
        )
    }

    fn same(a: &Dual<3>, b: &DualSVec64<3>) {
        assert_eq!(a.re.to_bits(), b.re.to_bits());
        let e = b.eps.unwrap_generic(Const::<3>, U1);
        for i in 0..3 {
            assert_eq!(a.eps[i].to_bits(), e[i].to_bits(), "slot {i}: {a} vs {b}");
        }
    }

    /// Every kind of operation the physics uses, in any dual type.
    fn expression<D: DualNum<f64> + Copy>(x: D, y: D, z: D) -> D {
        let (s, c) = x.sin_cos();
        (s * y - c / z + x.powi(3) * 0.25 - y.abs().sqrt() + z.ln() * x.exp() - (x * y).atan2(z)
            + z.powf(0.85)
            + x.tanh()
            + y.recip())
            / (z - 1.0)
    }

    /// The same expressions in both types give the same bits: the operations and chain rules
    /// are num-dual's.
    #[test]
    fn agrees_with_num_dual_bit_for_bit() {
        let (x, xs) = both(0.7, 0);
        let (y, ys) = both(-1.3, 1);
        let (z, zs) = both(2.9, 2);
        let f = expression::<Dual<3>>;
        same(&f(x, y, z), &expression(xs, ys, zs));
        // Derivatives against central differences of the value.
        let h = 1e-6;
        let r = f(x, y, z);
        for i in 0..3 {
            let mut p = [0.7, -1.3, 2.9];
            let mut m = p;
            p[i] += h;
            m[i] -= h;
            let v = |q: [f64; 3]| f(Dual::from(q[0]), Dual::from(q[1]), Dual::from(q[2])).re;
            let fd = (v(p) - v(m)) / (2.0 * h);
            assert!((r.eps[i] - fd).abs() < 1e-7 * fd.abs().max(1.0), "slot {i}");
        }
    }

    /// The physics' trigonometry (`Scalar::sine_cosine`, the libm crate's) agrees with std's
    /// to an ulp over the angles a rig reaches, and carries the chain rule in both dual types.
    #[test]
    fn physics_trigonometry_is_stds_to_an_ulp_with_its_derivatives() {
        use crate::model::Scalar;
        let mut worst: f64 = 0.0;
        for i in 0..20_001 {
            let x = -20.0 + 40.0 * f64::from(i) / 20_000.0;
            let (s, c) = x.sine_cosine();
            assert_eq!((s, c), (x.sine(), x.cosine()));
            for (a, b) in [(s, x.sin()), (c, x.cos())] {
                let ulp = f64::EPSILON * b.abs().max(f64::MIN_POSITIVE);
                worst = worst.max((a - b).abs() / ulp);
            }
        }
        assert!(worst <= 1.0, "{worst} ulp");
        let x = Dual::<3>::variable(0.7, 1);
        let (s, c) = x.sine_cosine();
        assert_eq!((s.re, c.re), (0.7f64.sine(), 0.7f64.cosine()));
        assert_eq!((s.eps[1], c.eps[1]), (0.7f64.cosine(), -0.7f64.sine()));
        assert_eq!((s.eps[0], c.eps[2]), (0.0, 0.0));
        assert_eq!(x.sine().eps[1], s.eps[1]);
        assert_eq!(x.cosine().eps[1], c.eps[1]);
        let y = num_dual::Dual64::new(0.7, 2.0).sine_cosine();
        assert_eq!(
            (y.0.eps, y.1.eps),
            (2.0 * 0.7f64.cosine(), -2.0 * 0.7f64.sine())
        );
    }

    /// A square root at zero of a constant keeps a zero derivative (num-dual's none), where
    /// a plain chain rule would give 0 * NaN = NaN; the variable's own slot is not finite.
    #[test]
    fn a_constants_infinite_derivative_stays_zero() {
        let c = Dual::<3>::from(0.0).sqrt();
        assert_eq!(c.re, 0.0);
        assert!(c.eps.iter().all(|&e| e == 0.0));
        let v = Dual::<3>::variable(0.0, 1).sqrt();
        assert!(!v.eps[1].is_finite());
        assert_eq!(v.eps[0], 0.0);
    }
}
