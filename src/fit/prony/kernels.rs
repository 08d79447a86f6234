//! What a domain gives the Prony core: each data row k observes
//! E∞·xₖ + Σ Eᵢ·hₖ(τᵢ), the input xₖ fixed and the kernel hₖ(τ) computed for any τ.
//!
//! - Time domain (a relaxation curve): xₖ the loading x(tₖ), hₖ(τ) the hereditary
//!   state ∫ e^(−(tₖ−s)/τ) dx(s) ([`crate::material::viscoelastic::Schedule`]).
//! - Frequency domain (a DMA sweep): a storage row has x = 1 and
//!   h = ω²τ²/(1 + ω²τ²), a loss row x = 0 and h = ωτ/(1 + ω²τ²)
//!   ([`super::frequency`]).

/// The rows of a Prony problem in one domain.
pub trait Kernels: Clone + Send + Sync {
    /// The words naming the τ window in messages ("the sampled time window").
    const WINDOW: &'static str;

    /// Number of rows.
    fn len(&self) -> usize;

    /// True if there are no rows.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The input xₖ of every row: the column of E∞.
    fn input(&self) -> &[f64];

    /// Where a pass over the rows stands between blocks of them
    /// ([`Kernels::kernel_rows`]): a time-domain kernel is a recursion from row to
    /// row, a frequency-domain one carries nothing.
    type Carry: Default + Clone + std::fmt::Debug + Send + Sync;

    /// The kernels hₖ(τ) of every τ of `taus` at the rows `rows` into `h`, one block
    /// of `rows.len()` values a τ end to end (the columns of a column-major matrix),
    /// and ∂h/∂τ into `dh` if given, the same layout. `carry` is where the pass
    /// stands: a fresh one starts at row 0, and each call leaves it where the next
    /// block (the same τ, with derivatives or not alike) starts. A pass a block at a
    /// time gives the bits of one over all rows.
    fn kernel_rows(
        &self,
        taus: &[f64],
        rows: std::ops::Range<usize>,
        carry: &mut Self::Carry,
        h: &mut [f64],
        dh: Option<&mut [f64]>,
    );

    /// [`Kernels::kernel_rows`] of all the rows in one pass.
    fn kernels(&self, taus: &[f64], h: &mut [f64], dh: Option<&mut [f64]>) {
        let rows = 0..self.len();
        self.kernel_rows(taus, rows, &mut Self::Carry::default(), h, dh);
    }

    /// Each row's noise group, where the rows are of kinds whose weighted residuals
    /// have different variances (a DMA fit's storage and loss rows): the
    /// assessment estimates a variance per group. None (the default): one variance.
    fn noise_groups(&self) -> Option<Vec<usize>> {
        None
    }

    /// The same domain on the rows `idx` (increasing); None where that cannot be
    /// built.
    fn subsample(&self, idx: &[usize]) -> Option<Self>;

    /// The finding for a term (`name`: "τ2 = 3 s") whose τ lies outside `window`,
    /// below it when `short`: why its τ and modulus are not determined.
    fn outside_window(name: &str, short: bool, window: (f64, f64)) -> String;
}
