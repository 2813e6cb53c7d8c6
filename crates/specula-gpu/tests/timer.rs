//! Stage timing: GPU timestamps where available, CPU wall clock otherwise; both report stages
//! in order with non-negative times, and say which source they used.

use specula_gpu::{test_context, StageTimer, TimingSource};

fn busy_stage(ctx: &specula_gpu::GpuContext) {
    // Clearing a large float target is real GPU work.
    let texture = ctx.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: 512,
            height: 512,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::RED),
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    });
    ctx.queue.submit([encoder.finish()]);
}

#[test]
fn stages_are_timed_by_the_best_available_source() {
    let Some(mut ctx) = test_context("stage timer") else {
        return;
    };
    for source in [ctx.timing, TimingSource::CpuWallClock] {
        ctx.timing = source;
        let mut timer = StageTimer::default();
        timer.start(Some(&ctx));
        busy_stage(&ctx);
        timer.lap(Some(&ctx), "first").unwrap();
        busy_stage(&ctx);
        busy_stage(&ctx);
        timer.lap(Some(&ctx), "second").unwrap();
        let (stages, used) = timer.finish(Some(&ctx)).unwrap();
        assert_eq!(used, source);
        assert_eq!(
            stages.iter().map(|s| s.stage.as_str()).collect::<Vec<_>>(),
            ["first", "second"]
        );
        assert!(stages
            .iter()
            .all(|s| s.milliseconds >= 0.0 && s.milliseconds.is_finite()));
        assert!(
            stages.iter().map(|s| s.milliseconds).sum::<f64>() > 0.0,
            "{source:?}: {stages:?}"
        );
    }
}

#[test]
fn a_reused_timer_creates_nothing_after_its_first_frame() {
    let Some(ctx) = test_context("stage timer reuse") else {
        return;
    };
    let mut timer = StageTimer::default();
    let mut frame = |ctx: &specula_gpu::GpuContext| {
        timer.start(Some(ctx));
        timer.lap(Some(ctx), "only").unwrap();
        timer.finish(Some(ctx)).unwrap()
    };
    frame(&ctx);
    let before = ctx.resource_counts();
    let (stages, _) = frame(&ctx);
    assert_eq!(stages.len(), 1);
    assert_eq!(ctx.resource_counts(), before);
}
