//! `twin view`: a finished run's output folder in the browser — the world, the paths, the robot
//! replayed scan by scan, the 3D model — served on 127.0.0.1 by a small HTTP server. The page,
//! its script and three.js (vendored, `sim/web/vendor/three/`) are inside the binary; the run's
//! files are read from the folder on each request.

use std::io::Read as _;
use std::path::{Path, PathBuf};

/// The page and its assets, compiled in: (URL path, content type, bytes).
const ASSETS: &[(&str, &str, &[u8])] = &[
    (
        "/",
        "text/html; charset=utf-8",
        include_bytes!("../../web/index.html"),
    ),
    (
        "/viewer.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/viewer.js"),
    ),
    (
        "/vendor/three/three.module.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/vendor/three/three.module.js"),
    ),
    (
        "/vendor/three/three.core.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/vendor/three/three.core.js"),
    ),
    (
        "/vendor/three/OrbitControls.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/vendor/three/OrbitControls.js"),
    ),
    (
        "/vendor/three/PLYLoader.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/vendor/three/PLYLoader.js"),
    ),
    (
        "/vendor/three/LICENSE",
        "text/plain; charset=utf-8",
        include_bytes!("../../web/vendor/three/LICENSE"),
    ),
];

/// The run's files the page may ask for (`/run/NAME`), with their content types. Nothing else
/// of the folder (or the disk) is served.
const RUN_FILES: &[(&str, &str)] = &[
    ("summary.json", "application/json"),
    ("world.json", "application/json"),
    ("truth.tum", "text/plain; charset=utf-8"),
    ("odometry.tum", "text/plain; charset=utf-8"),
    ("estimate.tum", "text/plain; charset=utf-8"),
    ("scans.jsonl", "text/plain; charset=utf-8"),
    ("sonar.json", "application/json"),
    ("reconstruction.json", "application/json"),
    ("model.ply", "application/octet-stream"),
];

/// Why `twin view` cannot serve.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The folder is not a run's output.
    #[error(
        "{}: not a run's output folder (no summary.json): give the folder `twin run`, `twin drive` or `twin map` wrote, e.g. out/lab-tour",
        .0.display()
    )]
    NotARun(PathBuf),
    /// The port cannot be bound.
    #[error("cannot listen on 127.0.0.1:{port}: {message}")]
    Listen {
        /// The port asked for.
        port: u16,
        /// Why.
        message: String,
    },
}

/// `twin view`: serve a finished run's output folder as a web page on 127.0.0.1.
#[derive(Clone, Debug, clap::Args)]
pub struct ViewArgs {
    /// The run's output folder (e.g. out/lab-tour).
    pub dir: PathBuf,
    /// The port (0: any free port; the address is printed).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
}

/// A response: status, content type, body.
type Reply = (u16, &'static str, Vec<u8>);

/// What the server answers to a GET of `url` for the run in `dir`.
pub fn answer(dir: &Path, url: &str) -> Reply {
    let path = url.split(['?', '#']).next().unwrap_or("/");
    if let Some((_, kind, bytes)) = ASSETS.iter().find(|(p, _, _)| *p == path) {
        return (200, kind, bytes.to_vec());
    }
    if let Some(name) = path.strip_prefix("/run/") {
        return match RUN_FILES.iter().find(|(n, _)| *n == name) {
            Some((name, kind)) => match std::fs::read(dir.join(name)) {
                Ok(bytes) => (200, kind, bytes),
                Err(e) => (
                    404,
                    "text/plain; charset=utf-8",
                    format!("{name}: not in this run's folder ({e})").into_bytes(),
                ),
            },
            None => (
                404,
                "text/plain; charset=utf-8",
                format!("{name}: not a file the viewer serves").into_bytes(),
            ),
        };
    }
    (
        404,
        "text/plain; charset=utf-8",
        format!("{path}: no such page").into_bytes(),
    )
}

/// Checks that `dir` is a run's output folder.
pub fn check_run_dir(dir: &Path) -> Result<(), ViewError> {
    if dir.join("summary.json").is_file() {
        Ok(())
    } else {
        Err(ViewError::NotARun(dir.to_path_buf()))
    }
}

/// Runs `twin view` until interrupted.
pub fn main(args: ViewArgs) -> Result<(), super::CommandError> {
    check_run_dir(&args.dir)?;
    let server =
        tiny_http::Server::http(("127.0.0.1", args.port)).map_err(|e| ViewError::Listen {
            port: args.port,
            message: e.to_string(),
        })?;
    let address = server
        .server_addr()
        .to_ip()
        .map_or_else(|| format!("127.0.0.1:{}", args.port), |a| a.to_string());
    say!("serving {} at http://{address}/", args.dir.display());
    say!("(Ctrl-C to stop)");
    for mut request in server.incoming_requests() {
        // The page's self-check (`/?selftest`, run by the browser test) reports here.
        if *request.method() == tiny_http::Method::Post && request.url() == "/selftest" {
            let mut body = String::new();
            let _ = std::io::Read::take(request.as_reader(), 1 << 20).read_to_string(&mut body);
            say!("selftest {}", body.replace('\n', " "));
            let _ = request.respond(tiny_http::Response::empty(204));
            continue;
        }
        let (status, kind, body) = answer(&args.dir, request.url());
        let header = tiny_http::Header::from_bytes(&b"Content-Type"[..], kind.as_bytes())
            .expect("a valid header");
        let response = tiny_http::Response::from_data(body)
            .with_status_code(status)
            .with_header(header);
        // A browser that went away mid-answer is not an error of the server.
        let _ = request.respond(response);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_page_its_assets_and_the_runs_own_files_are_served() {
        let dir = std::env::temp_dir().join(format!("twin-view-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("summary.json"), "{}").unwrap();
        assert_eq!(answer(&dir, "/").0, 200);
        assert_eq!(answer(&dir, "/?selftest=1").0, 200);
        assert_eq!(answer(&dir, "/vendor/three/three.module.js").0, 200);
        assert_eq!(
            answer(&dir, "/run/summary.json"),
            (200, "application/json", b"{}".to_vec())
        );
        let (status, _, body) = answer(&dir, "/run/model.ply");
        assert_eq!(status, 404);
        assert!(String::from_utf8_lossy(&body).starts_with("model.ply: not in this run's folder"));
        assert_eq!(answer(&dir, "/run/../../etc/passwd").0, 404);
        assert_eq!(answer(&dir, "/etc/passwd").0, 404);
        assert!(check_run_dir(&dir).is_ok());
        assert!(check_run_dir(&dir.join("nothing")).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
