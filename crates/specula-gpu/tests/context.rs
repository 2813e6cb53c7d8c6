//! The GPU context on this machine's Vulkan adapter (lavapipe without a GPU).

use specula_gpu::{test_context, GpuError};

fn clear_texture(
    ctx: &specula_gpu::GpuContext,
    width: u32,
    height: u32,
    color: wgpu::Color,
) -> wgpu::Texture {
    let texture = ctx.create_texture(&wgpu::TextureDescriptor {
        label: Some("target"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = texture.create_view(&Default::default());
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(color),
                store: wgpu::StoreOp::Store,
            },
        })],
        ..Default::default()
    });
    ctx.queue.submit([encoder.finish()]);
    texture
}

#[test]
fn float_render_target_reads_back_with_row_alignment() {
    let Some(ctx) = test_context("float_render_target_reads_back_with_row_alignment") else {
        return;
    };
    eprintln!("adapter: {}, timing: {:?}", ctx.describe(), ctx.timing);
    // 13 texels × 16 bytes = 208 bytes per row: padded to 256 on the GPU side.
    let color = wgpu::Color {
        r: 0.25,
        g: 1.5,
        b: -2.0,
        a: 1.0,
    };
    let texture = clear_texture(&ctx, 13, 5, color);
    let bytes = ctx.read_texture(&texture, 0).unwrap();
    let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    assert_eq!(texels.len(), 13 * 5);
    assert!(
        texels.iter().all(|t| *t == [0.25, 1.5, -2.0, 1.0]),
        "{:?}",
        &texels[..2]
    );
}

#[test]
fn validation_errors_are_values_not_panics() {
    let Some(ctx) = test_context("validation_errors_are_values_not_panics") else {
        return;
    };
    let result = ctx.validated("bad buffer", || {
        // MAP_READ may only be combined with COPY_DST: a validation error.
        ctx.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bad"),
            size: 16,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    });
    match result {
        Err(GpuError::Validation { stage, .. }) => assert_eq!(stage, "bad buffer"),
        Err(e) => panic!("wrong error {e}"),
        Ok(_) => panic!("invalid buffer accepted"),
    }
    assert!(ctx.validated("fine", || 1 + 1).is_ok());
}

#[test]
fn errors_outside_scopes_come_back_from_wait_instead_of_panicking() {
    let Some(ctx) = test_context("errors_outside_scopes") else {
        return;
    };
    let _bad = ctx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("bad"),
        size: 16,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    assert!(matches!(ctx.wait(), Err(GpuError::Validation { .. })));
    assert!(ctx.wait().is_ok(), "reported once");
}

/// An arena never asks the device for a buffer past its largest: such a reservation is an error
/// naming the arena and both sizes, and the arena stays usable; room given back is reused.
#[test]
fn an_arena_refuses_room_past_the_device_s_largest_buffer() {
    let Some(ctx) = test_context("arena limits") else {
        return;
    };
    let limit = ctx.device.limits().max_buffer_size;
    let mut arena = specula_gpu::arena::Arena::new("test vertices", wgpu::BufferUsages::VERTEX, 4);
    match arena.reserve(&ctx, [limit + 4]) {
        Err(error @ GpuError::TooLarge { .. }) => {
            let message = error.to_string();
            assert!(
                message.contains("test vertices") && message.contains(&limit.to_string()),
                "{message}"
            );
        }
        other => panic!("expected TooLarge, got {other:?}"),
    }
    assert!(arena.reserve(&ctx, [1024]).unwrap());
    let mark = arena.used();
    arena.push(&ctx, &[0u8; 1024]);
    arena.rewind(mark);
    assert_eq!(arena.used(), mark);
    // The room given back takes the next push without growing.
    assert!(!arena.reserve(&ctx, [1024]).unwrap());
}
