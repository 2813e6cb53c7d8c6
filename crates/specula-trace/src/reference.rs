pub fn render() {}
pub struct RenderSettings;
