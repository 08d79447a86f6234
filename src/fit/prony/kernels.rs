//! What a domain gives the Prony core: each data row k observes
//! E∞·xₖ + Σ Eᵢ·hₖ(τᵢ), the input xₖ fixed and the kernel hₖ(τ) computed for any τ.
//!
//! - Time domain (a relaxation curve): xₖ the loading x(tₖ), hₖ(τ) the hereditary
//!   state ∫ e^(−(tₖ−s)/τ) dx(s) ([`crate::material::viscoelastic::Schedule`]).
//! - Frequency domain (a DMA sweep): a storage row has x = 1 and
//!   h = ω²τ²/(1 + ω²τ²), a loss row x = 0 and h = ωτ/(1 + ω²τ²)
//!   ([`super::frequency`]).

use nalgebra::DMatrix;

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

    /// The uncertainty of the shifts the rows' abscissae were built with (a master
    /// curve's isotherms, each moved by an uncertain log10 aT, and log10 bT): the
    /// assessment adds what it does to the parameters. None (the default): the
    /// abscissae are exact.
    fn shift_covariance(&self) -> Option<&ShiftCovariance> {
        None
    }

    /// The same domain on the rows `idx` (increasing); None where that cannot be
    /// built.
    fn subsample(&self, idx: &[usize]) -> Option<Self>;

    /// The finding for a term (`name`: "τ2 = 3 s") whose τ lies outside `window`,
    /// below it when `short`: why its τ and modulus are not determined.
    fn outside_window(name: &str, short: bool, window: (f64, f64)) -> String;
}

/// The uncertainty of the shifts that built a data set from groups of rows (the
/// isotherms of a time–temperature master curve): group g's abscissa was multiplied
/// by a_g = 10^(log10 a_g) and its values divided by b_g = 10^(log10 b_g), each
/// uncertain. A kernel that depends on ωτ alone moves with log10 a_g as with every
/// τ of the group's rows together, so a shift's error is an error of the data the
/// fit cannot see in its residuals ([`super::assess`] propagates it).
#[derive(Debug, Clone, PartialEq)]
pub struct ShiftCovariance {
    /// Each row's group.
    pub group: Vec<usize>,
    /// The covariance of the groups' horizontal shifts log10 a_g (decades²).
    pub horizontal: DMatrix<f64>,
    /// The covariance of their vertical shifts log10 b_g, where there are.
    pub vertical: Option<DMatrix<f64>>,
}

impl ShiftCovariance {
    /// The same shifts on the rows `idx`.
    pub fn rows(&self, idx: &[usize]) -> ShiftCovariance {
        ShiftCovariance {
            group: idx.iter().map(|&i| self.group[i]).collect(),
            ..self.clone()
        }
    }

    /// The covariance of all the shifts, horizontal then vertical (decades²).
    pub fn joint(&self) -> DMatrix<f64> {
        let h = self.horizontal.nrows();
        let v = self.vertical.as_ref().map_or(0, |v| v.nrows());
        let mut c = DMatrix::zeros(h + v, h + v);
        c.view_mut((0, 0), (h, h)).copy_from(&self.horizontal);
        if let Some(vert) = &self.vertical {
            c.view_mut((h, h), (v, v)).copy_from(vert);
        }
        c
    }
}
