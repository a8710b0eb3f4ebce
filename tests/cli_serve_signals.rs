//! `raykit serve` stops gracefully on SIGTERM as on Ctrl-C (SIGINT): a
//! connected WebSocket client gets a close frame with code 1001 (going
//! away), the server says it is shutting down and exits with status 0.
//! The client is a minimal WebSocket client over a plain TCP socket
//! (RFC 6455 framing), independent of the server's WebSocket library.

#![cfg(unix)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

/// A running `raykit serve`, killed when dropped (as when a test fails
/// before it stops by itself).
struct Running(Child);

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `raykit serve` on a free port with small frames, and the address it
/// printed; its standard error is read up to that line.
fn start() -> (Running, String, BufReader<std::process::ChildStderr>) {
    let child = Command::new(env!("CARGO_BIN_EXE_raykit"))
        .args(["serve", "--addr", "127.0.0.1:0", "--width", "64"])
        .args(["--height", "48", "--seconds", "120"])
        .env_remove("RAYKIT_TOKEN")
        .stderr(Stdio::piped())
        .spawn()
        .expect("the raykit binary runs");
    let mut running = Running(child);
    let mut stderr = BufReader::new(running.0.stderr.take().unwrap());
    let mut line = String::new();
    loop {
        line.clear();
        if stderr.read_line(&mut line).unwrap() == 0 {
            panic!("the server ended before printing its address");
        }
        if let Some(rest) = line.split("http://").nth(1) {
            let addr = rest.split('/').next().unwrap().to_string();
            return (running, addr, stderr);
        }
    }
}

/// A server frame: its opcode and payload.
fn read_frame(s: &mut TcpStream) -> (u8, Vec<u8>) {
    let mut head = [0u8; 2];
    s.read_exact(&mut head).unwrap();
    let len = match head[1] & 0x7f {
        126 => {
            let mut b = [0u8; 2];
            s.read_exact(&mut b).unwrap();
            u16::from_be_bytes(b) as usize
        }
        127 => {
            let mut b = [0u8; 8];
            s.read_exact(&mut b).unwrap();
            u64::from_be_bytes(b) as usize
        }
        n => n as usize,
    };
    assert_eq!(head[1] & 0x80, 0, "a server frame is not masked");
    let mut payload = vec![0u8; len];
    s.read_exact(&mut payload).unwrap();
    (head[0] & 0x0f, payload)
}

/// Connect to `/ws` and read the hello.
fn connect(addr: &str) -> TcpStream {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    write!(
        s,
        "GET /ws HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    .unwrap();
    let mut head = Vec::new();
    while !head.ends_with(b"\r\n\r\n") {
        let mut b = [0u8; 1];
        s.read_exact(&mut b).unwrap();
        head.push(b[0]);
    }
    let head = String::from_utf8_lossy(&head);
    assert!(head.starts_with("HTTP/1.1 101"), "{head}");
    let (op, hello) = read_frame(&mut s);
    assert_eq!(op, 1, "the first message is text");
    assert!(String::from_utf8_lossy(&hello).contains("\"hello\""));
    s
}

#[test]
fn sigterm_and_sigint_close_clients_with_going_away_and_exit_zero() {
    for (signal, name) in [(libc::SIGTERM, "SIGTERM"), (libc::SIGINT, "Ctrl-C")] {
        let (mut server, addr, mut stderr) = start();
        let mut ws = connect(&addr);
        // SAFETY: kill(2) on the id of a child this test started and has
        // not yet waited for, so the id is still that child's.
        let sent = unsafe { libc::kill(server.0.id() as libc::pid_t, signal) };
        assert_eq!(sent, 0, "{name}: kill failed");
        let close = loop {
            let (op, payload) = read_frame(&mut ws);
            if op == 8 {
                break payload;
            }
        };
        let code = close.get(..2).map(|b| u16::from_be_bytes([b[0], b[1]]));
        let status = server.0.wait().unwrap();
        let mut rest = String::new();
        stderr.read_to_string(&mut rest).unwrap();
        assert_eq!(code, Some(1001), "{name}: close frame {close:?}; {rest}");
        assert!(status.success(), "{name}: {status}; {rest}");
        assert!(
            rest.contains(name) && rest.contains("shutting down"),
            "{name}: {rest}"
        );
    }
}
