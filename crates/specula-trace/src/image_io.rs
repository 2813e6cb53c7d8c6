pub struct Image;
pub struct ImageError;
