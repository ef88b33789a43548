//! Folders of camera images: the PNG and JPEG files of a directory, in file-name order, read
//! one at a time as 8-bit grey images (colour converted to luma, `ITU-R BT.601`, as the
//! `image` crate does). The only way raypath reads image files.
//!
//! ```no_run
//! use raypath_io::images::ImageFolder;
//! let folder = ImageFolder::open(std::path::Path::new("nordland/summer"))?;
//! let first = folder.read(0)?;
//! println!("{} images of {}×{} px", folder.len(), first.width(), first.height());
//! # Ok::<(), raypath_io::Error>(())
//! ```

use std::path::{Path, PathBuf};

use image::GrayImage;

use crate::{Error, Location, Result};

/// The image files of a directory, sorted by file name; nothing is decoded on opening.
#[derive(Clone, Debug)]
pub struct ImageFolder {
    dir: PathBuf,
    files: Vec<PathBuf>,
}

/// True for the extensions read as images (`png`, `jpg`, `jpeg`, any case).
pub fn is_image_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "png" | "jpg" | "jpeg"))
}

impl ImageFolder {
    /// Lists the PNG/JPEG files of `dir` (other files are skipped). Errors when `dir` is not a
    /// readable directory or holds no image file.
    pub fn open(dir: &Path) -> Result<Self> {
        let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, Location::File, e))?;
        let mut files = Vec::new();
        for entry in entries {
            let entry = entry.map_err(|e| Error::io(dir, Location::File, e))?;
            let path = entry.path();
            if is_image_file(&path) && path.is_file() {
                files.push(path);
            }
        }
        if files.is_empty() {
            return Err(Error::UnknownFormat {
                path: dir.to_path_buf(),
                reason: "no PNG or JPEG image in this folder".into(),
            });
        }
        files.sort_by(|a, b| a.file_name().cmp(&b.file_name()));
        Ok(Self {
            dir: dir.to_path_buf(),
            files,
        })
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Number of images.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// True when there is no image (never, for a folder from [`ImageFolder::open`]).
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// Keeps the first `n` images.
    pub fn truncate(&mut self, n: usize) {
        self.files.truncate(n);
    }

    /// The image files, in order.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// The file name of image `i` (lossy UTF-8), `None` out of range.
    pub fn name(&self, i: usize) -> Option<String> {
        let name = self.files.get(i)?.file_name()?;
        Some(name.to_string_lossy().into_owned())
    }

    /// Decodes image `i` as 8-bit grey. Errors name the file.
    pub fn read(&self, i: usize) -> Result<GrayImage> {
        let path = self.files.get(i).ok_or_else(|| Error::UnknownFormat {
            path: self.dir.clone(),
            reason: format!("no image {i} (the folder has {})", self.files.len()),
        })?;
        read_gray(path)
    }

    /// [`read`](Self::read), and an error naming the file unless the image is
    /// `width × height` pixels.
    pub fn read_sized(&self, i: usize, width: u32, height: u32) -> Result<GrayImage> {
        let image = self.read(i)?;
        if image.dimensions() != (width, height) {
            return Err(Error::malformed(
                &self.files[i],
                Location::File,
                format!(
                    "the image is {}×{} px, the others are {width}×{height} px",
                    image.width(),
                    image.height()
                ),
            ));
        }
        Ok(image)
    }
}

/// Decodes a PNG or JPEG file as 8-bit grey. Errors name the file.
pub fn read_gray(path: &Path) -> Result<GrayImage> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, Location::File, e))?;
    decode_gray(&bytes, path)
}

/// Decodes PNG or JPEG bytes as 8-bit grey; `name` is used in errors.
pub fn decode_gray(bytes: &[u8], name: &Path) -> Result<GrayImage> {
    let image = image::load_from_memory(bytes).map_err(|e| {
        Error::malformed(name, Location::File, format!("not a PNG/JPEG image: {e}"))
    })?;
    Ok(image.to_luma8())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(width: u32, height: u32, value: u8) -> Vec<u8> {
        let image = GrayImage::from_pixel(width, height, image::Luma([value]));
        let mut bytes = Vec::new();
        image
            .write_to(
                &mut std::io::Cursor::new(&mut bytes),
                image::ImageFormat::Png,
            )
            .expect("encode to memory");
        bytes
    }

    #[test]
    fn lists_images_in_name_order_and_reads_them() {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join("b.png"), png(4, 2, 20)).expect("write");
        std::fs::write(dir.path().join("a.PNG"), png(4, 2, 10)).expect("write");
        std::fs::write(dir.path().join("notes.txt"), b"not an image").expect("write");
        let folder = ImageFolder::open(dir.path()).expect("folder");
        assert_eq!(folder.len(), 2);
        assert_eq!(folder.name(0).as_deref(), Some("a.PNG"));
        assert_eq!(folder.read(0).expect("decode").get_pixel(3, 1).0, [10]);
        assert_eq!(
            folder
                .read_sized(1, 4, 2)
                .expect("decode")
                .get_pixel(0, 0)
                .0,
            [20]
        );
    }

    #[test]
    fn bad_folders_and_files_give_errors_naming_them() {
        let dir = tempfile::tempdir().expect("temp dir");
        let empty = ImageFolder::open(dir.path()).expect_err("empty folder");
        assert!(empty.to_string().contains("no PNG or JPEG"), "{empty}");
        let missing = ImageFolder::open(&dir.path().join("absent")).expect_err("missing");
        assert!(missing.to_string().contains("absent"), "{missing}");
        std::fs::write(dir.path().join("fake.png"), b"plain text").expect("write");
        std::fs::write(dir.path().join("big.png"), png(8, 8, 0)).expect("write");
        let folder = ImageFolder::open(dir.path()).expect("folder");
        let fake = folder.read(1).expect_err("not a PNG");
        assert!(fake.to_string().contains("fake.png"), "{fake}");
        let size = folder.read_sized(0, 4, 2).expect_err("wrong size");
        assert!(size.to_string().contains("big.png") && size.to_string().contains("8×8"));
        assert!(folder.read(7).is_err());
    }
}
