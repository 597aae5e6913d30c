//! Glue to `isoforge-slice`: the printer profiles the page offers (the project's own,
//! built into the binary, and any `.toml` profile in the model's folder), slicing to
//! G-code, and the SL1 archive for resin printers.

use std::io::Cursor;

use isoforge_slice::{
    GcodeJob, GridSpec, Profile, ProfileError, SliceError, Source, Technology, render_layers_from,
    sl1, slice_gcode,
};
use serde::Serialize;

use crate::folder::ModelFolder;
use crate::model::Loaded;

/// The project's printer profiles (fixtures/printers), compiled in so the studio offers
/// them wherever it runs.
const BUILTIN: &[(&str, &str)] = &[
    (
        "generic_marlin_220.toml",
        include_str!("../../../fixtures/printers/generic_marlin_220.toml"),
    ),
    (
        "prusa_mk3.toml",
        include_str!("../../../fixtures/printers/prusa_mk3.toml"),
    ),
    (
        "prusa_sl1.toml",
        include_str!("../../../fixtures/printers/prusa_sl1.toml"),
    ),
];

/// Prefix of a built-in profile's id; a folder profile's id is its file name.
const BUILTIN_PREFIX: &str = "builtin:";

/// A profile as the page lists it.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileInfo {
    /// What the page sends back to choose it.
    pub id: String,
    /// The profile's `name`, else its file name.
    pub name: String,
    /// `fdm` or `resin`.
    pub technology: &'static str,
    /// The build plate, mm (x, y).
    pub plate: [f64; 2],
    /// The printable height, mm.
    pub height: f64,
}

/// Why a profile could not be had.
#[derive(Debug, thiserror::Error)]
pub enum ProfileChoiceError {
    /// No profile by that id.
    #[error("no printer profile {0:?}")]
    Unknown(String),
    /// The name is not a file of the folder.
    #[error(transparent)]
    Folder(#[from] crate::folder::FolderError),
    /// The profile does not read or validate.
    #[error(transparent)]
    Profile(#[from] ProfileError),
}

/// Every profile on offer: the built-in ones first, then the folder's that read as
/// profiles (other `.toml` files are left out).
pub fn profiles(folder: &ModelFolder) -> Vec<ProfileInfo> {
    let builtin = BUILTIN
        .iter()
        .map(|(name, _)| format!("{BUILTIN_PREFIX}{name}"));
    let own = folder.files_with(&["toml"]).into_iter();
    builtin
        .chain(own)
        .filter_map(|id| {
            let p = profile(folder, &id).ok()?;
            info(&id, &p)
        })
        .collect()
}

/// The profile with this id.
pub fn profile(folder: &ModelFolder, id: &str) -> Result<Profile, ProfileChoiceError> {
    if let Some(name) = id.strip_prefix(BUILTIN_PREFIX) {
        let (_, text) = BUILTIN
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| ProfileChoiceError::Unknown(id.to_string()))?;
        return Ok(Profile::parse(text, name)?);
    }
    let path = folder.resolve(id)?;
    Ok(Profile::load(&path)?)
}

fn info(id: &str, p: &Profile) -> Option<ProfileInfo> {
    let name = p.raw("name").and_then(|v| v.as_str()).map_or_else(
        || id.trim_start_matches(BUILTIN_PREFIX).to_string(),
        str::to_string,
    );
    match p.technology() {
        Technology::Fdm => {
            let s = p.fdm().ok()?;
            Some(ProfileInfo {
                id: id.to_string(),
                name,
                technology: "fdm",
                plate: s.bed_size,
                height: s.max_height,
            })
        }
        Technology::Resin => {
            let r = p.resin().ok()?;
            Some(ProfileInfo {
                id: id.to_string(),
                name,
                technology: "resin",
                plate: [
                    f64::from(r.resolution[0]) * r.pixel_size,
                    f64::from(r.resolution[1]) * r.pixel_size,
                ],
                height: r.max_height,
            })
        }
    }
}

/// Slices a model to G-code with an FDM profile.
pub fn gcode(model: &Loaded, profile: &Profile) -> Result<GcodeJob, SliceError> {
    let settings = profile.fdm()?;
    slice_gcode(
        &Source::field(&model.shape, model.bounds),
        &settings,
        &|_, _| {},
    )
}

/// Slices a model into an SL1 archive with a resin profile; `job` names the layers inside.
pub fn sl1_archive(model: &Loaded, profile: &Profile, job: &str) -> Result<Vec<u8>, SliceError> {
    let r = profile.resin()?;
    let spec = GridSpec::Display {
        width: r.resolution[0],
        height: r.resolution[1],
        pixel: r.pixel_size,
        frame: r.frame(),
    };
    let source = Source::field(&model.shape, model.bounds);
    // As `isoforge slice --sl1`: the display's orientation and the resin's own first layer.
    let images = render_layers_from(
        &source,
        r.first_layer_height,
        r.layer_height,
        spec,
        &|_, _| {},
    )?;
    let thumb = sl1::thumbnail(
        &images.silhouette,
        images.silhouette_size.0,
        images.silhouette_size.1,
        sl1::THUMBNAIL,
    )?;
    let mut buf = Cursor::new(Vec::new());
    sl1::write_sl1(&mut buf, &images, &r, job, &thumb)?;
    Ok(buf.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_profiles_are_listed_with_their_plates() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("notes.toml"), "title = 'not a profile'").unwrap();
        std::fs::write(
            dir.path().join("mine.toml"),
            include_str!("../../../fixtures/printers/generic_marlin_220.toml")
                .replace("Generic Marlin 220", "My printer"),
        )
        .unwrap();
        let folder = ModelFolder::open(dir.path()).unwrap();
        let list = profiles(&folder);
        let ids: Vec<&str> = list.iter().map(|p| p.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "builtin:generic_marlin_220.toml",
                "builtin:prusa_mk3.toml",
                "builtin:prusa_sl1.toml",
                "mine.toml"
            ]
        );
        assert_eq!(list[0].plate, [220.0, 220.0]);
        assert_eq!(list[2].technology, "resin");
        assert_eq!(list[3].name, "My printer");
        assert!(matches!(
            profile(&folder, "builtin:nope.toml"),
            Err(ProfileChoiceError::Unknown(_))
        ));
        assert!(matches!(
            profile(&folder, "../x.toml"),
            Err(ProfileChoiceError::Folder(_))
        ));
    }
}
