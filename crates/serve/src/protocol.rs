//! The messages of the WebSocket protocol (see `PROTOCOL.md`): what clients
//! send, the JSON header in front of each frame (JPEG or raw RGB), and the
//! frame layout.

use raykit_core::glam::Vec3;
use raykit_core::Camera;
use serde::{Deserialize, Serialize};

/// A camera on the wire: eye, target, up and vertical field of view in
/// degrees. In requests each field is optional and defaults to the current
/// camera's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraJson {
    /// Eye point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eye: Option<[f32; 3]>,
    /// Point looked at.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target: Option<[f32; 3]>,
    /// Up direction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<[f32; 3]>,
    /// Vertical field of view, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov: Option<f32>,
}

impl CameraJson {
    /// Every field of `camera`.
    pub fn from_camera(camera: &Camera) -> Self {
        CameraJson {
            eye: Some(camera.eye.to_array()),
            target: Some(camera.target.to_array()),
            up: Some(camera.up.to_array()),
            fov: Some(camera.vfov_deg),
        }
    }

    /// `base` with the fields given here replaced.
    pub fn apply(&self, base: &Camera) -> Camera {
        Camera {
            eye: self.eye.map(Vec3::from_array).unwrap_or(base.eye),
            target: self.target.map(Vec3::from_array).unwrap_or(base.target),
            up: self.up.map(Vec3::from_array).unwrap_or(base.up),
            vfov_deg: self.fov.unwrap_or(base.vfov_deg),
        }
    }
}

/// One client message: an optional input sequence number and the request.
#[derive(Clone, Debug, PartialEq, Deserialize)]
pub struct Envelope {
    /// Increasing input number, echoed as `input_seq` by the first frame
    /// showing the input.
    #[serde(default)]
    pub seq: Option<u64>,
    /// The request.
    #[serde(flatten)]
    pub message: ClientMessage,
}

/// What a client asks for.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum ClientMessage {
    /// Frame `frame` was shown; the next may be sent.
    Ack {
        /// The frame number from its header.
        frame: u64,
    },
    /// Turn around the target by `yaw` and `pitch` radians.
    Orbit {
        /// About the up axis.
        #[serde(default)]
        yaw: f32,
        /// Towards the up axis.
        #[serde(default)]
        pitch: f32,
    },
    /// Move eye and target sideways, in eye-target distances.
    Pan {
        /// Along the camera's right axis.
        #[serde(default)]
        x: f32,
        /// Along the camera's up axis.
        #[serde(default)]
        y: f32,
    },
    /// Scale the eye-target distance.
    Zoom {
        /// Factor in `0.01..=100`.
        factor: f32,
    },
    /// Move in the camera frame, in scene diagonals.
    Fly {
        /// Along the view.
        #[serde(default)]
        forward: f32,
        /// Along the camera's right axis.
        #[serde(default)]
        right: f32,
        /// Along the camera's up axis.
        #[serde(default)]
        up: f32,
    },
    /// Device orientation angles in degrees (W3C `DeviceOrientationEvent`).
    Orient {
        /// About the earth's up axis.
        #[serde(default)]
        alpha: f32,
        /// About the device's x axis.
        #[serde(default)]
        beta: f32,
        /// About the device's y axis.
        #[serde(default)]
        gamma: f32,
    },
    /// Set the camera (fields optional).
    Camera(CameraJson),
    /// Back to the default camera. A struct variant with no fields (not a
    /// unit variant, whose extra fields serde would ignore), so that any
    /// field besides `type` and the envelope's `seq` is refused by name.
    Reset {},
    /// Full resolution, JPEG quality and refined samples per pixel.
    Settings(SettingsJson),
}

/// Client settings; absent fields stay as they are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingsJson {
    /// Full-resolution width.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// Full-resolution height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<u32>,
    /// JPEG quality, 1..=100.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quality: Option<u8>,
    /// Samples per pixel of the refined stage.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
    /// Frame payload format.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<FrameFormat>,
    /// Whether frames rendered while the camera moves are half-size
    /// previews (`true`, the default) or full size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub previews: Option<bool>,
}

/// How a frame's pixels are sent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameFormat {
    /// Baseline JPEG at the client's quality.
    #[default]
    Jpeg,
    /// Uncompressed 8-bit RGB, rows top to bottom, `3 × width × height`
    /// bytes: what a remote display without a decoder takes.
    Raw,
}

/// How far a frame has refined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    /// Camera moving: half the full size, one sample.
    Preview,
    /// Camera still: full size, one sample.
    Full,
    /// Full size, the client's samples per pixel.
    Refined,
}

impl Stage {
    /// The stage after this one when the view stays still, if any (`Full`
    /// is last when only one sample per pixel is asked for).
    pub fn next(self, spp: u32) -> Option<Stage> {
        match self {
            Stage::Preview => Some(Stage::Full),
            Stage::Full if spp > 1 => Some(Stage::Refined),
            _ => None,
        }
    }
}

/// The JSON header in front of every frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameHeader {
    /// Frame number on this connection, from 1.
    pub frame: u64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Refinement stage.
    pub stage: Stage,
    /// Largest input `seq` the frame shows (0 before any).
    pub input_seq: u64,
    /// The camera it was rendered with.
    pub camera: CameraJson,
    /// Render time, ms.
    pub render_ms: f64,
    /// Payload format (absent in headers of servers that only send JPEG).
    #[serde(default)]
    pub format: FrameFormat,
    /// Encoding time (JPEG; 0 for raw), ms.
    pub encode_ms: f64,
    /// This client's frames per second over the last 2 s.
    pub fps: f64,
    /// Median input-to-frame time of this client's last 256 inputs, ms.
    pub latency_ms: Option<f64>,
    /// This client's bytes per second over the last 2 s.
    pub bytes_per_second: f64,
}

/// A binary frame message: header length (u32, little-endian), the JSON
/// header, the payload (JPEG or raw RGB, as the header's `format` says).
pub fn encode_frame(header: &FrameHeader, payload: &[u8]) -> Vec<u8> {
    let json = serde_json::to_vec(header).expect("frame header serializes");
    let mut out = Vec::with_capacity(4 + json.len() + payload.len());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(payload);
    out
}

/// Split a binary frame message into its header and payload bytes; a raw
/// payload must hold exactly `3 × width × height` bytes.
pub fn decode_frame(bytes: &[u8]) -> Result<(FrameHeader, &[u8]), String> {
    let len_bytes: [u8; 4] = bytes
        .get(..4)
        .and_then(|b| b.try_into().ok())
        .ok_or("frame shorter than its 4-byte header length")?;
    let len = u32::from_le_bytes(len_bytes) as usize;
    let json = bytes
        .get(4..4 + len)
        .ok_or_else(|| format!("frame header of {len} bytes runs past the message end"))?;
    let header: FrameHeader =
        serde_json::from_slice(json).map_err(|e| format!("frame header at byte 4: {e}"))?;
    let payload = &bytes[4 + len..];
    if header.format == FrameFormat::Raw {
        let want = 3 * header.width as u64 * header.height as u64;
        if payload.len() as u64 != want {
            return Err(format!(
                "raw {}x{} frame: payload at byte {} has {} bytes, expected {want}",
                header.width,
                header.height,
                4 + len,
                payload.len()
            ));
        }
    }
    Ok((header, payload))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelopes_parse_with_and_without_seq() {
        let e: Envelope = serde_json::from_str(r#"{"type":"orbit","yaw":0.5,"seq":7}"#).unwrap();
        assert_eq!(e.seq, Some(7));
        assert_eq!(
            e.message,
            ClientMessage::Orbit {
                yaw: 0.5,
                pitch: 0.0
            }
        );
        let e: Envelope = serde_json::from_str(r#"{"type":"camera","fov":30}"#).unwrap();
        assert_eq!(
            e.message,
            ClientMessage::Camera(CameraJson {
                fov: Some(30.0),
                ..CameraJson::default()
            })
        );
        let e: Envelope = serde_json::from_str(r#"{"type":"reset"}"#).unwrap();
        assert_eq!(e.message, ClientMessage::Reset {});
        let e: Envelope = serde_json::from_str(r#"{"type":"reset","seq":5}"#).unwrap();
        assert_eq!((e.seq, e.message), (Some(5), ClientMessage::Reset {}));
        assert!(serde_json::from_str::<Envelope>(r#"{"type":"warp"}"#).is_err());
        assert!(serde_json::from_str::<Envelope>(r#"{"type":"zoom"}"#).is_err());
        // A misspelt field, or one the message does not have, is an error
        // naming it, not ignored.
        for (typo, field) in [
            (
                r#"{"type":"camera","eye":[0,1,3],"taget":[9,9,9]}"#,
                "taget",
            ),
            (r#"{"type":"settings","widht":800}"#, "widht"),
            (r#"{"type":"orbit","yaw":0.1,"pich":0.2,"seq":3}"#, "pich"),
            (r#"{"type":"reset","fov":10}"#, "fov"),
            (r#"{"type":"reset","seq":5,"sqe":1}"#, "sqe"),
        ] {
            let e = serde_json::from_str::<Envelope>(typo).unwrap_err();
            let named = format!("unknown field `{field}`");
            assert!(e.to_string().contains(&named), "{typo}: {e}");
        }
    }

    #[test]
    fn frames_round_trip_and_truncation_is_an_error() {
        let header = FrameHeader {
            frame: 3,
            width: 4,
            height: 2,
            spp: 1,
            stage: Stage::Preview,
            input_seq: 9,
            camera: CameraJson::default(),
            render_ms: 1.5,
            format: FrameFormat::Jpeg,
            encode_ms: 0.25,
            fps: 20.0,
            latency_ms: None,
            bytes_per_second: 100.0,
        };
        let bytes = encode_frame(&header, b"JPEG");
        let (h, jpeg) = decode_frame(&bytes).unwrap();
        assert_eq!((h, jpeg), (header.clone(), &b"JPEG"[..]));
        assert!(decode_frame(&bytes[..3]).is_err());
        assert!(decode_frame(&bytes[..10]).is_err());
        // A raw payload must match the size; headers without a format are
        // JPEG.
        let raw = FrameHeader {
            format: FrameFormat::Raw,
            ..header
        };
        let pixels: Vec<u8> = (0..24).collect();
        let bytes = encode_frame(&raw, &pixels);
        assert_eq!(decode_frame(&bytes).unwrap().1, &pixels[..]);
        assert!(decode_frame(&bytes[..bytes.len() - 1]).is_err());
        let legacy: FrameHeader = serde_json::from_str(
            r#"{"frame":1,"width":4,"height":2,"spp":1,"stage":"full","input_seq":0,
               "camera":{},"render_ms":1,"encode_ms":1,"fps":0,"latency_ms":null,
               "bytes_per_second":0}"#,
        )
        .unwrap();
        assert_eq!(legacy.format, FrameFormat::Jpeg);
        let s: SettingsJson = serde_json::from_str(r#"{"format":"raw","previews":false}"#).unwrap();
        assert_eq!(
            (s.format, s.previews),
            (Some(FrameFormat::Raw), Some(false))
        );
        assert!(serde_json::from_str::<SettingsJson>(r#"{"format":"png"}"#).is_err());
    }

    #[test]
    fn stages_refine_in_order() {
        assert_eq!(Stage::Preview.next(4), Some(Stage::Full));
        assert_eq!(Stage::Full.next(4), Some(Stage::Refined));
        assert_eq!(Stage::Full.next(1), None);
        assert_eq!(Stage::Refined.next(4), None);
    }
}
