//! Whether the model describes the recording: the residuals' RMS per marker, a noise-free
//! recording told apart, and the one plain sentence when the model limits the result.

use super::estimate::Estimate;
use super::uncertainty;

/// Below this many times the fit's relative tolerance times the rod length, a measured noise
/// and the residuals are below what the model's own positions resolve: the integrator's global
/// error over a recording's thousands of steps grows to hundreds of its local tolerance (a
/// noise-free 10 kHz recording leaves residuals of 1e-8 m at rtol 1e-9). At the default
/// tolerance this is 0.3 um on a 0.3 m rod, far below any camera's noise.
const NOISE_FREE_TOLERANCES: f64 = 1000.0;

/// Below this reduced chi-square the residuals are far smaller than the noise measured from the
/// tracks (no real noise gives it over the thousands of rows of a recording): the "noise" was
/// the smooth motion's leftover in the third differences, not noise.
const NOISE_FREE_CHI2: f64 = 0.01;

/// Whether a recording is noise-free for the fit (a synthetic recording written without
/// noise): its measured noise `sigma` and the residuals' RMS `rms` (m) both below [`NOISE_FREE_TOLERANCES`] x `rtol` x `scale` (the model's
/// numerical accuracy at the markers' distance), or the reduced chi-square below
/// [`NOISE_FREE_CHI2`]. Then the residuals are the integrator's and the data's rounding, and
/// the chi-square, block and window tests, which compare them with the noise, say nothing. A
/// model that misfits a noise-free recording leaves residuals far above the model's accuracy:
/// it is not noise-free and keeps its flag.
pub fn is_noise_free(sigma: [f64; 2], rms: f64, scale: f64, rtol: f64, reduced_chi2: f64) -> bool {
    sigma[0].max(sigma[1]).max(rms) < numerical_accuracy_m(rtol, scale)
        || reduced_chi2 < NOISE_FREE_CHI2
}

/// What the model's own marker positions resolve (m): [`NOISE_FREE_TOLERANCES`] x `rtol` x
/// `scale` (the markers' distance from the pivot). A residual below it is the integrator's,
/// not the data's.
pub fn numerical_accuracy_m(rtol: f64, scale: f64) -> f64 {
    NOISE_FREE_TOLERANCES * rtol * scale
}

/// The false-alarm rate of the adequacy tests together on a recording the model describes:
/// the chi-square, runs and slides tests share it (Bonferroni with unequal weights, so the
/// family's rate is at most their sum: [`CHI2_P`] + [`RUNS_P`] + [`WINDOWS_P`]). Each test at
/// its own 5 % flagged clean recordings and the flag then cost them their interval; a flag a
/// lab learns to ignore protects nobody.
pub const FAMILY_P: f64 = 0.01;

/// Below this p-value chi-square against the measured noise fails (its share of
/// [`FAMILY_P`]): a chi-square far beyond its thousands of degrees of freedom is the most
/// powerful of the tests against a missing effect, and needs the least of the rate.
pub const CHI2_P: f64 = 1e-3;

/// Below this p-value the runs test says the residuals are not noise (four streams of
/// thousands of signs: a smooth miss of 3/4 of the noise is enough, whatever noise was
/// measured). Its share of [`FAMILY_P`] is the smallest: tracker noise correlated over a few
/// frames shortens nothing but still lengthens runs a little, and that is carried by the
/// block covariance, not called a misfit.
pub const RUNS_P: f64 = 1e-4;

/// Below this p-value the slides, fitted one by one, disagree on mu_kinetic: the rest of
/// [`FAMILY_P`]. With four to six slides the test has little power; what it misses is carried
/// by the windows' scale factor only where it fires, so that a clean recording keeps its
/// interval.
pub const WINDOWS_P: f64 = FAMILY_P - CHI2_P - RUNS_P;

/// An adequacy test the fit failed, with the figure that failed it. Each test's threshold
/// lives in [`failed_tests`] alone: the verdict, its sentence and the report's one-line
/// answer all read it from there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FailedTest {
    /// Chi-square against the measured noise, p < [`CHI2_P`] (its p-value).
    ChiSquare(f64),
    /// The residuals' signs run in long stretches, p < [`RUNS_P`] (its p-value).
    Runs(f64),
    /// The slides, fitted one by one, disagree, p < [`WINDOWS_P`] (its p-value).
    Slides(f64),
}

/// The adequacy tests failed by a fit with chi-square p-value `p_value`, runs-test p-value
/// `runs_p` and windows' agreement `windows_p` (in the order the report says them): one
/// family whose false-alarm rate on a recording the model describes is at most [`FAMILY_P`].
/// Residuals correlated in time are no test: the block covariance carries them into the
/// standard error whenever they widen it, and a model that fits is not called a misfit for
/// the tracker's correlated noise.
pub fn failed_tests(p_value: f64, runs_p: f64, windows_p: Option<f64>) -> Vec<FailedTest> {
    let mut failed = Vec::new();
    if p_value < CHI2_P {
        failed.push(FailedTest::ChiSquare(p_value));
    }
    if runs_p < RUNS_P {
        failed.push(FailedTest::Runs(runs_p));
    }
    if let Some(p) = windows_p.filter(|p| *p < WINDOWS_P) {
        failed.push(FailedTest::Slides(p));
    }
    failed
}

/// Why a result is limited by the model, in the order the report says it: prose the fit
/// wrote (a value no real rig has, every free parameter taken, mu pinned at a bound), or the
/// adequacy tests that failed, as numbers the report words (`report::fit::limited_sentence`).
#[derive(Debug, Clone, PartialEq)]
pub enum LimitPart {
    /// A sentence of the fit's.
    Said(String),
    /// The adequacy tests that failed.
    Tests(FailedTests),
}

/// The adequacy tests a fit failed ([`failed_tests`]), with the chi-square they were read
/// from, and mu_kinetic's widened interval and its method when mu was fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct FailedTests {
    /// The tests that failed, with their p-values.
    pub tests: Vec<FailedTest>,
    /// Chi-square against the measured noise.
    pub chi2: f64,
    /// Its degrees of freedom.
    pub dof: f64,
    /// chi2 / dof.
    pub reduced_chi2: f64,
    /// mu_kinetic's 95 % interval and its method (`profile+block+windows`, ...).
    pub mu_interval: Option<([f64; 2], &'static str)>,
}

/// The tests of [`failed_tests`] that failed, as a part of why the model limits the result
/// (`None` when none failed), with what the widened interval of `mu` holds.
pub(super) fn failed_part(
    a: &uncertainty::Assessment,
    windows_p: Option<f64>,
    runs_p: f64,
    mu: Option<&Estimate>,
) -> Option<LimitPart> {
    let tests = failed_tests(a.p_value, runs_p, windows_p);
    (!tests.is_empty()).then(|| {
        LimitPart::Tests(FailedTests {
            tests,
            chi2: a.chi2,
            dof: a.dof,
            reduced_chi2: a.reduced_chi2,
            mu_interval: mu.map(|e| (e.ci95, e.interval)),
        })
    })
}
