//! A series kept in bounded memory: every sample until [`Decimated::CAPACITY`], then every
//! second one, every fourth, … (the stride doubles each time the series fills), and always the
//! latest. Plots and segment figures of any run need no more; a day's run at 250 Hz
//! (21.6 million cycles) would otherwise keep gigabytes.

/// A series of `T`, at most [`Decimated::CAPACITY`] samples plus the latest.
#[derive(Debug, Clone)]
pub struct Decimated<T> {
    kept: Vec<T>,
    latest: Option<T>,
    stride: u64,
    seen: u64,
}

impl<T> Default for Decimated<T> {
    fn default() -> Self {
        Self {
            kept: Vec::new(),
            latest: None,
            stride: 1,
            seen: 0,
        }
    }
}

impl<T: Clone> Decimated<T> {
    /// Samples kept before the stride doubles: 4.4 simulated minutes at 250 Hz at full rate.
    pub const CAPACITY: usize = 1 << 16;

    /// Adds a sample.
    pub fn push(&mut self, sample: T) {
        if self.seen % self.stride == 0 {
            if self.kept.capacity() == 0 {
                // Once, whole: the series never grows past it, so a run allocates nothing more
                // for it (pages are touched only as samples fill them).
                self.kept.reserve_exact(Self::CAPACITY);
            }
            self.kept.push(sample);
            self.latest = None;
            if self.kept.len() >= Self::CAPACITY {
                let mut index = 0;
                self.kept.retain(|_| {
                    index += 1;
                    index % 2 == 1
                });
                self.stride *= 2;
            }
        } else {
            self.latest = Some(sample);
        }
        self.seen += 1;
    }

    /// The samples kept, in order, the latest last.
    pub fn into_vec(mut self) -> Vec<T> {
        self.kept.extend(self.latest.take());
        self.kept
    }

    /// The samples kept, in order, without the latest unless it was kept.
    pub fn kept(&self) -> &[T] {
        &self.kept
    }

    /// The latest sample.
    pub fn last(&self) -> Option<&T> {
        self.latest.as_ref().or(self.kept.last())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_series_are_kept_whole_and_long_ones_bounded_with_the_latest() {
        let mut short = Decimated::default();
        for i in 0..1000_u64 {
            short.push(i);
        }
        assert_eq!(short.into_vec(), (0..1000).collect::<Vec<_>>());
        let mut long = Decimated::default();
        let n = 5 * Decimated::<u64>::CAPACITY as u64 + 7;
        for i in 0..n {
            long.push(i);
        }
        assert_eq!(long.last(), Some(&(n - 1)));
        let kept = long.into_vec();
        assert!(
            kept.len() <= Decimated::<u64>::CAPACITY + 1,
            "{}",
            kept.len()
        );
        assert!(kept.len() >= Decimated::<u64>::CAPACITY / 2);
        assert_eq!(kept.first(), Some(&0));
        assert_eq!(kept.last(), Some(&(n - 1)));
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
    }
}
