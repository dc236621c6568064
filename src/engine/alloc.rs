//! Fallible reservation of the engines' large buffers (junction arrays, sum trees, bags):
//! an allocation that fails becomes an [`AllocError`], reported in one line, instead of the
//! abort that `Vec`'s infallible growth ends in.

/// A buffer could not be allocated.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "out of memory: cannot allocate {bytes} bytes for {what} (junctions.n = {n}); lower junctions.n or free memory"
)]
pub struct AllocError {
    /// What the buffer holds.
    pub what: &'static str,
    /// Bytes asked for (saturated at `u64::MAX`).
    pub bytes: u64,
    /// Its length in elements (the scene's `junctions.n`, or a size derived from it).
    pub n: usize,
}

/// An empty vector with room for exactly `n` elements, or the error naming `what`.
pub fn with_capacity<T>(n: usize, what: &'static str) -> Result<Vec<T>, AllocError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| AllocError {
        what,
        bytes: (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
        n,
    })?;
    Ok(v)
}

/// `n` copies of `value` (like `vec![value; n]`), or the error naming `what`.
pub fn filled<T: Clone>(n: usize, value: T, what: &'static str) -> Result<Vec<T>, AllocError> {
    let mut v = with_capacity(n, what)?;
    v.resize(n, value);
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_impossible_size_is_an_error_not_an_abort() {
        let e = filled::<f64>(usize::MAX / 4, 0.0, "the test buffer").unwrap_err();
        assert_eq!(e.what, "the test buffer");
        assert_eq!(e.bytes, u64::MAX);
        let line = e.to_string();
        assert!(line.contains("junctions.n") && !line.contains('\n'), "{line}");
        let e = with_capacity::<[u8; 64]>(1 << 58, "lines").unwrap_err();
        assert_eq!(e.bytes, u64::MAX);
    }

    #[test]
    fn a_possible_size_is_exact() {
        let v = filled(1000, 7u8, "bytes").unwrap();
        assert_eq!((v.len(), v.capacity()), (1000, 1000));
        assert!(v.iter().all(|&b| b == 7));
        assert_eq!(with_capacity::<u32>(10, "ids").unwrap().capacity(), 10);
    }
}
