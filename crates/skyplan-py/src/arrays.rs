//! Python values in, checked: 2-D numeric numpy arrays, coordinate pairs, keyword options as
//! JSON. Every refusal is a `skyplan.BadInput` naming the argument.

use crate::errors::bad_input;
use numpy::{PyArray2, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};

/// Element types read from numpy arrays, as `f64`.
trait AsF64: Copy {
    fn as_f64(self) -> f64;
}

impl AsF64 for f64 {
    fn as_f64(self) -> f64 {
        self
    }
}

impl AsF64 for bool {
    fn as_f64(self) -> f64 {
        if self { 1.0 } else { 0.0 }
    }
}

macro_rules! as_f64_by_cast {
    ($($t:ty),*) => {$(
        impl AsF64 for $t {
            #[allow(clippy::cast_precision_loss)]
            fn as_f64(self) -> f64 {
                self as f64
            }
        }
    )*};
}
as_f64_by_cast!(f32, i8, i16, i32, i64, u8, u16, u32, u64);

/// `obj` as a numpy array (array-likes such as nested lists through `numpy.asarray`).
fn ndarray<'py>(obj: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyUntypedArray>> {
    if let Ok(a) = obj.cast::<PyUntypedArray>() {
        return Ok(a.clone());
    }
    let converted = obj
        .py()
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| bad_input(format!("{what}: expected a numpy array: {e}")))?;
    converted
        .cast_into::<PyUntypedArray>()
        .map_err(|_| bad_input(format!("{what}: expected a numpy array")))
}

/// A 2-D numeric array (bool, integers or floats, any memory layout) as its shape and its
/// values in row-major order, each mapped by `f`.
pub(crate) fn map2<R>(
    obj: &Bound<'_, PyAny>,
    what: &str,
    f: impl FnMut(f64) -> R,
) -> PyResult<(usize, usize, Vec<R>)> {
    let arr = ndarray(obj, what)?;
    if arr.ndim() != 2 {
        return Err(bad_input(format!(
            "{what}: expected a 2-D array, got {} dimension(s), shape {:?}",
            arr.ndim(),
            arr.shape()
        )));
    }
    read2(&arr, what, f)
}

/// A 2-D numeric occupancy array as its shape and its cells in row-major order, `true` for
/// blocked (nonzero); NaN cells are refused.
pub(crate) fn blocked2(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(usize, usize, Vec<bool>)> {
    let mut nan = false;
    let (rows, cols, blocked) = map2(obj, what, |v| {
        nan |= v.is_nan();
        v != 0.0
    })?;
    if nan {
        return Err(bad_input(format!(
            "{what}: NaN cells (expected 0 for free, nonzero for blocked)"
        )));
    }
    Ok((rows, cols, blocked))
}

fn read2<R>(
    arr: &Bound<'_, PyUntypedArray>,
    what: &str,
    mut f: impl FnMut(f64) -> R,
) -> PyResult<(usize, usize, Vec<R>)> {
    macro_rules! try_types {
        ($($t:ty),*) => {$(
            if let Ok(a) = arr.cast::<PyArray2<$t>>() {
                let ro = a
                    .try_readonly()
                    .map_err(|e| bad_input(format!("{what}: {e}")))?;
                let view = ro.as_array();
                let (rows, cols) = view.dim();
                return Ok((rows, cols, view.iter().map(|&x| f(x.as_f64())).collect()));
            }
        )*};
    }
    try_types!(f64, bool, u8, i64, f32, i32, i8, i16, u16, u32, u64);
    Err(bad_input(format!(
        "{what}: expected a numeric array (bool, integer or float), got dtype {}",
        arr.dtype()
    )))
}

/// The item `k` of a sequence-like `obj` (tuple, list, array) of length `len`.
fn items<'py>(obj: &Bound<'py, PyAny>, len: usize, what: &str) -> PyResult<Vec<Bound<'py, PyAny>>> {
    let shape_err = || {
        bad_input(format!(
            "{what}: expected {len} numbers (a tuple, list or array), got {}",
            describe(obj)
        ))
    };
    if obj.is_instance_of::<PyString>() {
        return Err(shape_err());
    }
    let n = obj.len().map_err(|_| shape_err())?;
    if n != len {
        return Err(shape_err());
    }
    (0..len)
        .map(|k| obj.get_item(k).map_err(|_| shape_err()))
        .collect()
}

/// `repr(obj)`, shortened, for messages.
pub(crate) fn describe(obj: &Bound<'_, PyAny>) -> String {
    let text = obj
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "<unprintable>".into());
    if text.chars().count() > 80 {
        format!("{}…", text.chars().take(80).collect::<String>())
    } else {
        text
    }
}

/// Two integers (a grid cell `(row, col)`): Python ints or numpy integers, not floats.
pub(crate) fn int_pair(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[i64; 2]> {
    let v = items(obj, 2, what)?;
    let get = |x: &Bound<'_, PyAny>| -> PyResult<i64> {
        // Integers (Python's and numpy's) have `__index__`; floats, even integral ones, do not.
        if !x.hasattr("__index__").unwrap_or(false) {
            return Err(bad_input(format!(
                "{what}: expected integer (row, col) indices, got {}",
                describe(obj)
            )));
        }
        x.extract::<i64>().map_err(|_| {
            bad_input(format!(
                "{what}: expected integer (row, col) indices, got {}",
                describe(obj)
            ))
        })
    };
    Ok([get(&v[0])?, get(&v[1])?])
}

/// Two finite numbers.
pub(crate) fn float_pair(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; 2]> {
    let v = items(obj, 2, what)?;
    let get = |x: &Bound<'_, PyAny>| {
        finite(
            x.extract::<f64>().ok(),
            || format!("{what}: expected two numbers, got {}", describe(obj)),
            || format!("{what}: expected finite numbers, got {}", describe(obj)),
        )
    };
    Ok([get(&v[0])?, get(&v[1])?])
}

/// `value` if it is a finite number; else a `BadInput` with `not_number()` (for `None`: the
/// value was not a number) or `not_finite()` (NaN or infinite).
pub(crate) fn finite(
    value: Option<f64>,
    not_number: impl FnOnce() -> String,
    not_finite: impl FnOnce() -> String,
) -> PyResult<f64> {
    match value {
        None => Err(bad_input(not_number())),
        Some(v) if v.is_finite() => Ok(v),
        Some(_) => Err(bad_input(not_finite())),
    }
}

/// A Python value (numbers, strings, booleans, None, sequences, dicts, numpy scalars and
/// arrays) as JSON, for the planning API's serde types. NaN and infinities are refused.
pub(crate) fn to_json(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Value> {
    if obj.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if obj.is_instance_of::<PyInt>() {
        if let Ok(i) = obj.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = obj.extract::<u64>() {
            return Ok(Value::from(u));
        }
        return Err(bad_input(format!(
            "{what}: {} is out of range",
            describe(obj)
        )));
    }
    if obj.is_instance_of::<PyFloat>() {
        let v: f64 = obj.extract()?;
        return Number::from_f64(v)
            .map(Value::Number)
            .ok_or_else(|| bad_input(format!("{what}: expected a finite number, got {v}")));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.extract::<String>()?));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        let mut map = Map::new();
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| bad_input(format!("{what}: keys must be strings")))?;
            let value = to_json(&v, &format!("{what}.{key}"))?;
            map.insert(key, value);
        }
        return Ok(Value::Object(map));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        return obj
            .try_iter()?
            .enumerate()
            .map(|(k, item)| to_json(&item?, &format!("{what}[{k}]")))
            .collect::<PyResult<Vec<Value>>>()
            .map(Value::Array);
    }
    // numpy scalars and arrays: their plain Python equivalent.
    if obj.hasattr("tolist").unwrap_or(false) && obj.hasattr("dtype").unwrap_or(false) {
        let plain = obj.call_method0("tolist")?;
        if !plain.is(obj) {
            return to_json(&plain, what);
        }
    }
    Err(bad_input(format!(
        "{what}: cannot pass {} (type {}) as an option value",
        describe(obj),
        obj.get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_default()
    )))
}
