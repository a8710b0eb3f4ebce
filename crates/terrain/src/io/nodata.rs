//! The GDAL_NODATA value: its text form and how it matches float32 samples.

/// The float32 sample a nodata value stands for. GDAL writes -FLT_MAX in
/// text with too few digits (e.g. "-3.4028229999999999e+038"), so a value
/// within 1e-6 (relative) of ±f32::MAX means ±f32::MAX exactly.
pub fn nodata_as_f32(nodata: f64) -> f32 {
    let lim = f32::MAX as f64;
    if (nodata - lim).abs() <= 1e-6 * lim {
        f32::MAX
    } else if (nodata + lim).abs() <= 1e-6 * lim {
        f32::MIN
    } else {
        nodata as f32
    }
}

/// The float32 samples a nodata value marks: the value rounded to float32,
/// as GDAL compares them, and for a value within 1e-6 of ±f32::MAX also
/// ±f32::MAX ([`nodata_as_f32`]). GDAL writes -FLT_MAX as
/// "-3.4028229999999999e+038", and fills the cells of what it warps or
/// pads with that text rounded to float32 (-3.40282306e38, one step inside
/// -FLT_MAX), while files from other writers hold -FLT_MAX itself.
#[derive(Clone, Copy, Debug)]
pub struct NodataF32 {
    rounded: f32,
    extreme: f32,
}

impl NodataF32 {
    /// The samples `nodata` marks.
    pub fn new(nodata: f64) -> Self {
        NodataF32 {
            rounded: nodata as f32,
            extreme: nodata_as_f32(nodata),
        }
    }

    /// Whether `sample` is no data.
    #[inline]
    pub fn matches(self, sample: f32) -> bool {
        sample == self.rounded || sample == self.extreme
    }
}

/// The GDAL_NODATA text for `nodata`: `nan`, a plain decimal such as
/// `-9999` or `0.5`, or for very large or small magnitudes an exponent form
/// such as `-3.4028234663852886e38`; always parses back to the same f64.
pub fn nodata_text(nodata: f64) -> String {
    if nodata.is_nan() {
        "nan".to_string()
    } else if nodata == 0.0 || (1e-5..1e15).contains(&nodata.abs()) {
        format!("{nodata}")
    } else {
        format!("{nodata:e}")
    }
}
