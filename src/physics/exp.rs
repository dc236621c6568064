//! `e^x` inlined, for the weak-bond rate `k_off` of every junction-step of the fixed step:
//! the table method of the C libraries' `exp` (Tang's reduction, as in glibc since 2.28,
//! musl and Arm's optimized-routines), with the same table, polynomial and operation order
//! as glibc's FMA build, so it gives the same bits as `f64::exp` there, with no call and no
//! `errno` wrapper.
//!
//! ```text
//!     x = k ln2/N + r,  |r| <= ln2/(2N),  N = 128,
//!     e^x = 2^(k/N) e^r ~= s + s (t + r + r^2 (C2 + C3 r) + r^4 (C4 + C5 r)),
//! ```
//!
//! with `2^(j/N) = H_j (1 + T_j)` tabulated (`s = 2^(k div N) H_(k mod N)`, `t = T_(k mod N)`)
//! and the polynomial's coefficients the minimax fit of `e^r - 1 - r` on `|r| < ln2/256`
//! published with the method (Arm's optimized-routines, MIT or Apache-2.0; absolute error
//! `1.56 2^-66`): at most 0.509 ulp. Outside `2^-54 <= |x| < 512`
//! (where the scale could leave the normal range) and in builds without FMA it is
//! `f64::exp` itself.

/// `N/ln2`, `-ln2/N` in two parts, the coefficients `C2 .. C5`, and the shift that rounds
/// `x N/ln2` to an integer in the low bits of the sum.
const INV_LN2_N: f64 = f64::from_bits(0x40671547652b82fe); // 0x1.71547652b82fep7
const NEG_LN2_HI_N: f64 = f64::from_bits(0xbf762e42fefa0000); // -0x1.62e42fefa0000p-8
const NEG_LN2_LO_N: f64 = f64::from_bits(0xbd0cf79abc9e3b3a); // -0x1.cf79abc9e3b3ap-47
const C2: f64 = f64::from_bits(0x3fdffffffffffdbd); // 0x1.ffffffffffdbdp-2
const C3: f64 = f64::from_bits(0x3fc555555555543c); // 0x1.555555555543cp-3
const C4: f64 = f64::from_bits(0x3fa55555cf172b91); // 0x1.55555cf172b91p-5
const C5: f64 = f64::from_bits(0x3f81111167a4d017); // 0x1.1111167a4d017p-7
const SHIFT: f64 = f64::from_bits(0x4338000000000000); // 0x1.8p52

/// `[bits(T_j), bits(H_j) - (j << 45)]` for `j = 0 .. 128`: `H_j` is `2^(j/128)` rounded,
/// `T_j` the relative remainder rounded; `j << 45` taken off so that adding `k << 45` puts
/// `k div 128` into the exponent. Checked by `tests::table_is_the_roots_of_two`.
#[rustfmt::skip]
const TABLE: [u64; 256] = [
    0x0000000000000000, 0x3ff0000000000000, 0x3c9b3b4f1a88bf6e, 0x3feff63da9fb3335,
    0xbc7160139cd8dc5d, 0x3fefec9a3e778061, 0xbc905e7a108766d1, 0x3fefe315e86e7f85,
    0x3c8cd2523567f613, 0x3fefd9b0d3158574, 0xbc8bce8023f98efa, 0x3fefd06b29ddf6de,
    0x3c60f74e61e6c861, 0x3fefc74518759bc8, 0x3c90a3e45b33d399, 0x3fefbe3ecac6f383,
    0x3c979aa65d837b6d, 0x3fefb5586cf9890f, 0x3c8eb51a92fdeffc, 0x3fefac922b7247f7,
    0x3c3ebe3d702f9cd1, 0x3fefa3ec32d3d1a2, 0xbc6a033489906e0b, 0x3fef9b66affed31b,
    0xbc9556522a2fbd0e, 0x3fef9301d0125b51, 0xbc5080ef8c4eea55, 0x3fef8abdc06c31cc,
    0xbc91c923b9d5f416, 0x3fef829aaea92de0, 0x3c80d3e3e95c55af, 0x3fef7a98c8a58e51,
    0xbc801b15eaa59348, 0x3fef72b83c7d517b, 0xbc8f1ff055de323d, 0x3fef6af9388c8dea,
    0x3c8b898c3f1353bf, 0x3fef635beb6fcb75, 0xbc96d99c7611eb26, 0x3fef5be084045cd4,
    0x3c9aecf73e3a2f60, 0x3fef54873168b9aa, 0xbc8fe782cb86389d, 0x3fef4d5022fcd91d,
    0x3c8a6f4144a6c38d, 0x3fef463b88628cd6, 0x3c807a05b0e4047d, 0x3fef3f49917ddc96,
    0x3c968efde3a8a894, 0x3fef387a6e756238, 0x3c875e18f274487d, 0x3fef31ce4fb2a63f,
    0x3c80472b981fe7f2, 0x3fef2b4565e27cdd, 0xbc96b87b3f71085e, 0x3fef24dfe1f56381,
    0x3c82f7e16d09ab31, 0x3fef1e9df51fdee1, 0xbc3d219b1a6fbffa, 0x3fef187fd0dad990,
    0x3c8b3782720c0ab4, 0x3fef1285a6e4030b, 0x3c6e149289cecb8f, 0x3fef0cafa93e2f56,
    0x3c834d754db0abb6, 0x3fef06fe0a31b715, 0x3c864201e2ac744c, 0x3fef0170fc4cd831,
    0x3c8fdd395dd3f84a, 0x3feefc08b26416ff, 0xbc86a3803b8e5b04, 0x3feef6c55f929ff1,
    0xbc924aedcc4b5068, 0x3feef1a7373aa9cb, 0xbc9907f81b512d8e, 0x3feeecae6d05d866,
    0xbc71d1e83e9436d2, 0x3feee7db34e59ff7, 0xbc991919b3ce1b15, 0x3feee32dc313a8e5,
    0x3c859f48a72a4c6d, 0x3feedea64c123422, 0xbc9312607a28698a, 0x3feeda4504ac801c,
    0xbc58a78f4817895b, 0x3feed60a21f72e2a, 0xbc7c2c9b67499a1b, 0x3feed1f5d950a897,
    0x3c4363ed60c2ac11, 0x3feece086061892d, 0x3c9666093b0664ef, 0x3feeca41ed1d0057,
    0x3c6ecce1daa10379, 0x3feec6a2b5c13cd0, 0x3c93ff8e3f0f1230, 0x3feec32af0d7d3de,
    0x3c7690cebb7aafb0, 0x3feebfdad5362a27, 0x3c931dbdeb54e077, 0x3feebcb299fddd0d,
    0xbc8f94340071a38e, 0x3feeb9b2769d2ca7, 0xbc87deccdc93a349, 0x3feeb6daa2cf6642,
    0xbc78dec6bd0f385f, 0x3feeb42b569d4f82, 0xbc861246ec7b5cf6, 0x3feeb1a4ca5d920f,
    0x3c93350518fdd78e, 0x3feeaf4736b527da, 0x3c7b98b72f8a9b05, 0x3feead12d497c7fd,
    0x3c9063e1e21c5409, 0x3feeab07dd485429, 0x3c34c7855019c6ea, 0x3feea9268a5946b7,
    0x3c9432e62b64c035, 0x3feea76f15ad2148, 0xbc8ce44a6199769f, 0x3feea5e1b976dc09,
    0xbc8c33c53bef4da8, 0x3feea47eb03a5585, 0xbc845378892be9ae, 0x3feea34634ccc320,
    0xbc93cedd78565858, 0x3feea23882552225, 0x3c5710aa807e1964, 0x3feea155d44ca973,
    0xbc93b3efbf5e2228, 0x3feea09e667f3bcd, 0xbc6a12ad8734b982, 0x3feea012750bdabf,
    0xbc6367efb86da9ee, 0x3fee9fb23c651a2f, 0xbc80dc3d54e08851, 0x3fee9f7df9519484,
    0xbc781f647e5a3ecf, 0x3fee9f75e8ec5f74, 0xbc86ee4ac08b7db0, 0x3fee9f9a48a58174,
    0xbc8619321e55e68a, 0x3fee9feb564267c9, 0x3c909ccb5e09d4d3, 0x3feea0694fde5d3f,
    0xbc7b32dcb94da51d, 0x3feea11473eb0187, 0x3c94ecfd5467c06b, 0x3feea1ed0130c132,
    0x3c65ebe1abd66c55, 0x3feea2f336cf4e62, 0xbc88a1c52fb3cf42, 0x3feea427543e1a12,
    0xbc9369b6f13b3734, 0x3feea589994cce13, 0xbc805e843a19ff1e, 0x3feea71a4623c7ad,
    0xbc94d450d872576e, 0x3feea8d99b4492ed, 0x3c90ad675b0e8a00, 0x3feeaac7d98a6699,
    0x3c8db72fc1f0eab4, 0x3feeace5422aa0db, 0xbc65b6609cc5e7ff, 0x3feeaf3216b5448c,
    0x3c7bf68359f35f44, 0x3feeb1ae99157736, 0xbc93091fa71e3d83, 0x3feeb45b0b91ffc6,
    0xbc5da9b88b6c1e29, 0x3feeb737b0cdc5e5, 0xbc6c23f97c90b959, 0x3feeba44cbc8520f,
    0xbc92434322f4f9aa, 0x3feebd829fde4e50, 0xbc85ca6cd7668e4b, 0x3feec0f170ca07ba,
    0x3c71affc2b91ce27, 0x3feec49182a3f090, 0x3c6dd235e10a73bb, 0x3feec86319e32323,
    0xbc87c50422622263, 0x3feecc667b5de565, 0x3c8b1c86e3e231d5, 0x3feed09bec4a2d33,
    0xbc91bbd1d3bcbb15, 0x3feed503b23e255d, 0x3c90cc319cee31d2, 0x3feed99e1330b358,
    0x3c8469846e735ab3, 0x3feede6b5579fdbf, 0xbc82dfcd978e9db4, 0x3feee36bbfd3f37a,
    0x3c8c1a7792cb3387, 0x3feee89f995ad3ad, 0xbc907b8f4ad1d9fa, 0x3feeee07298db666,
    0xbc55c3d956dcaeba, 0x3feef3a2b84f15fb, 0xbc90a40e3da6f640, 0x3feef9728de5593a,
    0xbc68d6f438ad9334, 0x3feeff76f2fb5e47, 0xbc91eee26b588a35, 0x3fef05b030a1064a,
    0x3c74ffd70a5fddcd, 0x3fef0c1e904bc1d2, 0xbc91bdfbfa9298ac, 0x3fef12c25bd71e09,
    0x3c736eae30af0cb3, 0x3fef199bdd85529c, 0x3c8ee3325c9ffd94, 0x3fef20ab5fffd07a,
    0x3c84e08fd10959ac, 0x3fef27f12e57d14b, 0x3c63cdaf384e1a67, 0x3fef2f6d9406e7b5,
    0x3c676b2c6c921968, 0x3fef3720dcef9069, 0xbc808a1883ccb5d2, 0x3fef3f0b555dc3fa,
    0xbc8fad5d3ffffa6f, 0x3fef472d4a07897c, 0xbc900dae3875a949, 0x3fef4f87080d89f2,
    0x3c74a385a63d07a7, 0x3fef5818dcfba487, 0xbc82919e2040220f, 0x3fef60e316c98398,
    0x3c8e5a50d5c192ac, 0x3fef69e603db3285, 0x3c843a59ac016b4b, 0x3fef7321f301b460,
    0xbc82d52107b43e1f, 0x3fef7c97337b9b5f, 0xbc892ab93b470dc9, 0x3fef864614f5a129,
    0x3c74b604603a88d3, 0x3fef902ee78b3ff6, 0x3c83c5ec519d7271, 0x3fef9a51fbc74c83,
    0xbc8ff7128fd391f0, 0x3fefa4afa2a490da, 0xbc8dae98e223747d, 0x3fefaf482d8e67f1,
    0x3c8ec3bc41aa2008, 0x3fefba1bee615a27, 0x3c842b94c3a9eb32, 0x3fefc52b376bba97,
    0x3c8a64a931d185ee, 0x3fefd0765b6e4540, 0xbc8e37bae43be3ed, 0x3fefdbfdad9cbe14,
    0x3c77893b4d91cd9d, 0x3fefe7c1819e90d8, 0x3c5305c14160cc89, 0x3feff3c22b8f71f1,
];

/// `e^x`, the same value as `f64::exp` (glibc's FMA build; within 0.51 ulp of the truth
/// elsewhere). Always inlined: a call and the library's `errno` wrapper would be half its cost.
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    // 2^-54 <= |x| < 512 (false for NaN).
    #[cfg(target_feature = "fma")]
    if (5.551_115_123_125_783e-17..512.0).contains(&x.abs()) {
        return table_method(x);
    }
    x.exp()
}

/// The module's method for `2^-54 <= |x| < 512` (each `mul_add` rounds once in any build;
/// without FMA instructions each is a library call, so [`exp`] uses it only with them).
#[cfg_attr(not(target_feature = "fma"), allow(dead_code))]
#[inline(always)]
fn table_method(x: f64) -> f64 {
    let kd = x.mul_add(INV_LN2_N, SHIFT);
    let ki = kd.to_bits();
    let kd = kd - SHIFT;
    let r = kd.mul_add(NEG_LN2_LO_N, kd.mul_add(NEG_LN2_HI_N, x));
    let j = 2 * (ki % 128) as usize;
    let tail = f64::from_bits(TABLE[j]);
    let scale = f64::from_bits(TABLE[j + 1].wrapping_add(ki << 45));
    let r2 = r * r;
    let lo = r.mul_add(C3, C2).mul_add(r2, r + tail);
    let tmp = (r2 * r2).mul_add(r.mul_add(C5, C4), lo);
    scale.mul_add(tmp, scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{UniformSource, pcg};
    use twofloat::TwoFloat;

    /// Ulps between two finite doubles of the same sign.
    fn ulps(a: f64, b: f64) -> u64 {
        a.to_bits().abs_diff(b.to_bits())
    }

    /// The table's `2^(j/128)`, `H_j (1 + T_j)`, as a double-double.
    fn root(j: usize) -> TwoFloat {
        let h = f64::from_bits(TABLE[2 * j + 1].wrapping_add((j as u64) << 45));
        TwoFloat::from(h) + TwoFloat::from(h * f64::from_bits(TABLE[2 * j]))
    }

    /// Every entry squared (in double-double arithmetic, error about `2^-104`) is the entry
    /// of the doubled exponent, times 2 past the end, and entry 0 is exactly 1: the only
    /// positive solution is `2^(j/128)`, so an entry wrong by more than `2^-100` of itself fails.
    #[test]
    fn table_is_the_roots_of_two() {
        assert_eq!(root(0), TwoFloat::from(1.0));
        for j in 0..128 {
            let want = if 2 * j < 128 { root(2 * j) } else { TwoFloat::from(2.0) * root(2 * j - 128) };
            let diff = (root(j) * root(j) - want).hi();
            assert!(diff.abs() <= want.hi() * 2f64.powi(-100), "entry {j}: squared off by {diff:e}");
        }
    }

    /// Correctly rounded `e^x` (60-digit decimal arithmetic): within an ulp (the method's
    /// bound is 0.509 ulp), across the fast path, its two ends and the library's range.
    #[test]
    fn within_an_ulp_of_the_truth() {
        let cases: [(f64, u64); 20] = [
            (1.0, 0x4005bf0a8b145769),
            (-1.0, 0x3fd78b56362cef38),
            (0.5, 0x3ffa61298e1e069c),
            (-0.5, 0x3fe368b2fc6f960a),
            (1e-10, 0x3ff000000006df38),
            (-3.7e-09, 0x3feffffffe0379d3),
            (5.551115123125783e-17, 0x3ff0000000000000),
            (10.0, 0x40d5829dcf950560),
            (-10.0, 0x3f07cd79b5647c9b),
            (std::f64::consts::LN_2, 0x4000000000000000),
            (std::f64::consts::PI, 0x403724046eb09339),
            (88.72283905206835, 0x47efffffdffffff5),
            (-87.3365447505531, 0x381000000000001e),
            (255.5, 0x56f8656b982d1f44),
            (-300.25, 0x24dc758233102ace),
            (511.99, 0x6e190700ce84c46d),
            (-511.99, 0x11c4752637d2e526),
            (0.001, 0x3ff0041919b7ee34),
            (-2.5e-05, 0x3fefffcb92651cce),
            (42.42, 0x43c25e36137cf9c7),
        ];
        for (x, truth) in cases {
            assert!(ulps(exp(x), f64::from_bits(truth)) <= 1, "exp({x}) = {:e}", exp(x));
            assert!(ulps(table_method(x), f64::from_bits(truth)) <= 1, "the method at {x}");
        }
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
        assert_eq!(exp(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp(f64::NEG_INFINITY), 0.0);
        assert!(exp(f64::NAN).is_nan());
        assert_eq!(exp(710.0), f64::INFINITY);
        assert_eq!(exp(-746.0), 0.0);
    }

    /// A million arguments over the method's range (uniform in `[-512, 512]`, in `[-1, 1]` and in
    /// magnitude from `2^-60` to `2^9`) against the system's `exp`: within an ulp, and the
    /// same bits where the system is glibc 2.28 or newer (its x86-64 FMA build is this
    /// method, operation for operation: the engines' outputs do not depend on which is used).
    #[test]
    fn agrees_with_the_system_exp() {
        let mut rng = pcg(2028);
        let mut differ = 0;
        for i in 0..1_000_000 {
            let u = rng.uniform();
            let x = match i % 3 {
                0 => 1024.0 * u - 512.0,
                1 => 2.0 * u - 1.0,
                _ => 2f64.powf(-60.0 + 69.0 * u) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 },
            };
            let (ours, system) = (table_method(x), x.exp());
            assert_eq!(exp(x).to_bits(), if cfg!(target_feature = "fma") { ours } else { system }.to_bits());
            assert!(ulps(ours, system) <= 1, "exp({x}): {ours:e} against {system:e}");
            differ += usize::from(ours != system);
        }
        if glibc_has_this_method() {
            assert_eq!(differ, 0, "bits differ from glibc's exp");
        }
    }

    /// Whether the system's `exp` is glibc's from 2.28 on, with FMA (the build's level, which
    /// the processor running it has: glibc picks its FMA build by the processor).
    fn glibc_has_this_method() -> bool {
        #[cfg(all(target_os = "linux", target_env = "gnu", target_feature = "fma"))]
        {
            // SAFETY: returns a pointer to a static NUL-terminated string.
            let version = unsafe { std::ffi::CStr::from_ptr(libc::gnu_get_libc_version()) };
            let mut parts = version.to_str().unwrap_or("0.0").split('.').map(|p| p.parse::<u32>().unwrap_or(0));
            let (major, minor) = (parts.next().unwrap_or(0), parts.next().unwrap_or(0));
            (major, minor) >= (2, 28)
        }
        #[cfg(not(all(target_os = "linux", target_env = "gnu", target_feature = "fma")))]
        false
    }
}
