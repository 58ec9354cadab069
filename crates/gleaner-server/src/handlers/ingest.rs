//! Readings uploads (multipart) and recorded flights.

use std::path::PathBuf;

use axum::Json;
use axum::extract::multipart::MultipartRejection;
use axum::extract::{Multipart, Path, State};
use axum::http::StatusCode;
use gleaner_app as app;

use crate::api::{IngestDoc, RecordDoc, parse_time};
use crate::auth::Writing;
use crate::error::{ApiError, ApiResult, ErrorBody};
use crate::state::{AppState, Changes};

use super::{clock_now, mission_id};

/// Multipart form parts of an upload: the files (saved into a temporary folder under
/// sanitised names) and the text fields.
struct Upload {
    _dir: tempfile::TempDir,
    files: Vec<PathBuf>,
    /// The client's name of each file (its last path component).
    names: Vec<String>,
    fields: Vec<(String, String)>,
}

impl Upload {
    /// Rewrites an error's message to name the client's files, not the temporary copies.
    fn client_names(&self, mut e: ApiError) -> ApiError {
        for (path, name) in self.files.iter().zip(&self.names) {
            e.body.reason = e.body.reason.replace(&path.display().to_string(), name);
        }
        e
    }

    fn field(&self, name: &str) -> Option<&str> {
        self.fields
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

/// A file name reduced to letters, digits, `.`, `-`, `_` (never a path), prefixed with its
/// position so two uploads of the same name stay apart.
fn safe_name(k: usize, name: &str) -> String {
    let base = name.rsplit(['/', '\\']).next().unwrap_or("");
    let clean: String = base
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_') {
                c
            } else {
                '_'
            }
        })
        .collect();
    let clean = clean.trim_start_matches('.');
    format!("{k:03}-{}", if clean.is_empty() { "upload" } else { clean })
}

fn multipart_type(r: MultipartRejection) -> ApiError {
    ApiError::unsupported_media_type(format!(
        "this endpoint takes a multipart/form-data upload: {}",
        r.body_text()
    ))
}

fn multipart_error(e: axum::extract::multipart::MultipartError) -> ApiError {
    if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
        ApiError::too_large(
            Some("files"),
            format!("the upload is too large: {}", e.body_text()),
        )
    } else {
        ApiError::bad_request(
            Some("files"),
            format!("bad multipart upload: {}", e.body_text()),
        )
    }
}

/// Reads a whole multipart upload to disk before any use case runs, so an upload cut off or
/// over the limit half-way stores nothing.
async fn read_upload(mut m: Multipart) -> ApiResult<Upload> {
    use tokio::io::AsyncWriteExt as _;
    let dir = tempfile::Builder::new()
        .prefix("gleaner-upload-")
        .tempdir()
        .map_err(|e| ApiError::internal(format!("cannot create a temporary folder: {e}")))?;
    let mut files = Vec::new();
    let mut names = Vec::new();
    let mut fields = Vec::new();
    while let Some(mut part) = m.next_field().await.map_err(multipart_error)? {
        let name = part.name().unwrap_or("").to_string();
        match part.file_name().map(str::to_string) {
            Some(file_name) => {
                let path = dir.path().join(safe_name(files.len(), &file_name));
                let mut out = tokio::fs::File::create(&path)
                    .await
                    .map_err(|e| ApiError::internal(format!("cannot store the upload: {e}")))?;
                while let Some(chunk) = part.chunk().await.map_err(multipart_error)? {
                    out.write_all(&chunk)
                        .await
                        .map_err(|e| ApiError::internal(format!("cannot store the upload: {e}")))?;
                }
                out.flush()
                    .await
                    .map_err(|e| ApiError::internal(format!("cannot store the upload: {e}")))?;
                files.push(path);
                names.push(
                    file_name
                        .rsplit(['/', '\\'])
                        .next()
                        .unwrap_or("")
                        .to_string(),
                );
            }
            None => {
                let text = part.text().await.map_err(multipart_error)?;
                fields.push((name, text));
            }
        }
    }
    Ok(Upload {
        _dir: dir,
        files,
        names,
        fields,
    })
}

fn format_of(text: Option<&str>) -> ApiResult<app::Format> {
    Ok(match text.unwrap_or("auto") {
        "auto" => app::Format::Auto,
        "long-csv" => app::Format::Long,
        "wide-csv" => app::Format::Wide,
        "caf-daily" => app::Format::CafDaily,
        "hubbard-brook" => app::Format::HubbardBrook,
        other => {
            return Err(ApiError::bad_request(
                Some("format"),
                format!(
                    "format {other:?}: expected auto, long-csv, wide-csv, caf-daily or hubbard-brook"
                ),
            ));
        }
    })
}

fn flag(upload: &Upload, name: &str) -> ApiResult<bool> {
    match upload.field(name) {
        None | Some("false") | Some("0") | Some("") => Ok(false),
        Some("true") | Some("1") | Some("on") => Ok(true),
        Some(v) => Err(ApiError::bad_request(
            Some(name),
            format!("{name} = {v:?}: expected true or false"),
        )),
    }
}

/// Ingests uploaded readings files (multipart: one or more `files` parts and optional
/// `format`, `modality`, `unit`, `utc_offset_h`, `on_error` fields), all or nothing.
#[utoipa::path(post, path = "/api/v1/ingest", tag = "data",
    request_body(content_type = "multipart/form-data", description = "files (one part per file); format = auto | long-csv | wide-csv | caf-daily | hubbard-brook; modality; unit; utc_offset_h; on_error = fail | skip"),
    security(("bearer" = [])),
    responses((status = 200, body = IngestDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn ingest(
    State(s): State<AppState>,
    _: Writing,
    m: Result<Multipart, MultipartRejection>,
) -> ApiResult<Json<IngestDoc>> {
    let m = m.map_err(multipart_type)?;
    let upload = read_upload(m).await?;
    if upload.files.is_empty() {
        return Err(ApiError::bad_request(
            Some("files"),
            "no file in the upload: send one or more `files` parts",
        ));
    }
    let utc_offset_h = match upload.field("utc_offset_h") {
        None | Some("") => 0.0,
        Some(v) => v
            .parse::<f64>()
            .ok()
            .filter(|h| h.is_finite())
            .ok_or_else(|| {
                ApiError::bad_request(
                    Some("utc_offset_h"),
                    format!("utc_offset_h = {v:?}: expected hours"),
                )
            })?,
    };
    let on_error = match upload.field("on_error") {
        None | Some("") | Some("fail") => app::OnError::Fail,
        Some("skip") => app::OnError::Skip,
        Some(v) => {
            return Err(ApiError::bad_request(
                Some("on_error"),
                format!("on_error = {v:?}: expected fail or skip"),
            ));
        }
    };
    let request = app::IngestRequest {
        files: upload.files.clone(),
        format: format_of(upload.field("format"))?,
        modality: upload
            .field("modality")
            .filter(|v| !v.is_empty())
            .map(str::to_string),
        unit: upload
            .field("unit")
            .filter(|v| !v.is_empty())
            .map(str::to_string),
        utc_offset_h,
        on_error,
        metadata: None,
        now: None,
    };
    let doc = s
        .run_write(Changes::ALL, false, move |p| {
            let out = app::ingest(p, &request, clock_now(), &app::Silent)
                .map_err(|e| upload.client_names(e.into()));
            Ok(IngestDoc::from_app(&out?))
        })
        .await?;
    Ok(Json(doc))
}

/// Records a flown mission (multipart: optional `at`, `cells` (comma-separated, in visiting
/// order), `amend`, and the readings files brought back as `files` parts). 409 when the
/// mission was already recorded and `amend` is not set.
#[utoipa::path(post, path = "/api/v1/missions/{id}/record", tag = "data",
    params(("id" = i64, Path, description = "Mission id")),
    request_body(content_type = "multipart/form-data", description = "at (RFC 3339 or date); cells (comma-separated ids); amend (true/false); files (readings brought back, any ingest format)"),
    security(("bearer" = [])),
    responses((status = 200, body = RecordDoc), (status = 400, body = ErrorBody),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody),
        (status = 413, body = ErrorBody)))]
pub async fn record(
    State(s): State<AppState>,
    _: Writing,
    Path(id): Path<String>,
    m: Result<Multipart, MultipartRejection>,
) -> ApiResult<Json<RecordDoc>> {
    let m = m.map_err(multipart_type)?;
    let id = mission_id(&id)?;
    let upload = read_upload(m).await?;
    let cells = upload
        .field("cells")
        .filter(|c| !c.trim().is_empty())
        .map(|c| c.split(',').map(|s| s.trim().to_string()).collect());
    let request = app::RecordRequest {
        mission: id,
        at: parse_time("at", upload.field("at").filter(|v| !v.is_empty()))?,
        cells,
        readings: (!upload.files.is_empty()).then(|| app::IngestRequest {
            files: upload.files.clone(),
            ..Default::default()
        }),
        amend: flag(&upload, "amend")?,
    };
    let doc = s
        .run_write(Changes::ALL, false, move |p| {
            let out = app::record_flight(p, &request, clock_now(), &app::Silent)
                .map_err(|e| upload.client_names(e.into()));
            Ok(RecordDoc::from_app(&out?))
        })
        .await?;
    Ok(Json(doc))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uploaded_names_never_become_paths() {
        assert_eq!(safe_name(0, "../../etc/passwd"), "000-passwd");
        assert_eq!(safe_name(1, "C:\\x\\..\\CAF003.txt"), "001-CAF003.txt");
        assert_eq!(safe_name(2, ".."), "002-upload");
        assert_eq!(safe_name(3, "a b;c.csv"), "003-a_b_c.csv");
    }
}
