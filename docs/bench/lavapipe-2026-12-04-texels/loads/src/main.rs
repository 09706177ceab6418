//! How fast lavapipe loads 16 bytes per invocation from a storage buffer, a sampled texture, a read-only
//! storage texture and a uniform buffer: 512x512 invocations, 64 dependent random loads each from 1 MiB
//! (docs/BENCHMARKS.md, "The CPU path"). Run from this folder with the workspace's Cargo.lock copied beside
//! it: `cp ../../../../Cargo.lock . && cargo run --offline`.
use std::time::Instant;
const N: u32 = 1 << 16; // elements
const W: u32 = 1024;
fn main() {
    let inst = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(inst.request_adapter(&Default::default())).unwrap();
    println!("{:?} ubo {}", adapter.get_info().name, adapter.limits().max_uniform_buffer_binding_size);
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor{required_limits: adapter.limits(), ..Default::default()})).unwrap();
    let mut data = vec![0u32; (N * 4) as usize];
    let mut s = 12345u32;
    for v in data.iter_mut() { s ^= s << 13; s ^= s >> 17; s ^= s << 5; *v = s; }
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::UNIFORM;
    let buf = device.create_buffer(&wgpu::BufferDescriptor{label:None,size:(N*16) as u64,usage,mapped_at_creation:false});
    queue.write_buffer(&buf, 0, bytemuck::cast_slice(&data));
    let ubuf = device.create_buffer(&wgpu::BufferDescriptor{label:None,size:65536,usage,mapped_at_creation:false});
    queue.write_buffer(&ubuf, 0, bytemuck::cast_slice(&data[..16384]));
    let tex = device.create_texture(&wgpu::TextureDescriptor{label:None,size:wgpu::Extent3d{width:W,height:N/W,depth_or_array_layers:1},mip_level_count:1,sample_count:1,dimension:wgpu::TextureDimension::D2,format:wgpu::TextureFormat::Rgba32Uint,usage:wgpu::TextureUsages::TEXTURE_BINDING|wgpu::TextureUsages::COPY_DST|wgpu::TextureUsages::STORAGE_BINDING,view_formats:&[]});
    queue.write_texture(wgpu::TexelCopyTextureInfo{texture:&tex,mip_level:0,origin:wgpu::Origin3d::ZERO,aspect:wgpu::TextureAspect::All}, bytemuck::cast_slice(&data), wgpu::TexelCopyBufferLayout{offset:0,bytes_per_row:Some(W*16),rows_per_image:None}, wgpu::Extent3d{width:W,height:N/W,depth_or_array_layers:1});
    let out = device.create_buffer(&wgpu::BufferDescriptor{label:None,size:4*65536*4,usage,mapped_at_creation:false});
    let variants = [
        ("storage", "@group(0) @binding(0) var<storage, read> d: array<vec4<u32>>;\nfn ld(i: u32) -> vec4<u32> { return d[i]; }"),
        ("storage-scalar-x", "@group(0) @binding(0) var<storage, read> d: array<vec4<u32>>;\nfn ld(i: u32) -> vec4<u32> { return vec4<u32>(d[i].x, 0u, 0u, 0u); }"),
        ("texture", "@group(0) @binding(0) var d: texture_2d<u32>;\nfn ld(i: u32) -> vec4<u32> { return textureLoad(d, vec2<u32>(i % 1024u, i / 1024u), 0); }"),
        ("texture-shift", "@group(0) @binding(0) var d: texture_2d<u32>;\nfn ld(i: u32) -> vec4<u32> { return textureLoad(d, vec2<u32>(i & 1023u, i >> 10u), 0); }"),
        ("storage-texture", "@group(0) @binding(0) var d: texture_storage_2d<rgba32uint, read>;\nfn ld(i: u32) -> vec4<u32> { return textureLoad(d, vec2<u32>(i & 1023u, i >> 10u)); }"),
        ("uniform", "@group(0) @binding(0) var<uniform> d: array<vec4<u32>, 4096>;\nfn ld(i: u32) -> vec4<u32> { return d[i & 4095u]; }"),
    ];
    for (name, decl) in variants {
        let src = format!("{decl}\n@group(0) @binding(1) var<storage, read_write> o: array<u32>;\n@compute @workgroup_size(8,8) fn main(@builtin(global_invocation_id) g: vec3<u32>) {{\n var i = (g.y * 512u + g.x) * 2654435761u;\n var acc = 0u;\n for (var k = 0u; k < 64u; k++) {{ let v = ld(i & {m}u); acc += v.x ^ v.y ^ v.z ^ v.w; i = v.x ^ (i >> 3u); }}\n o[g.y * 512u + g.x] = acc;\n}}", m = N - 1);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor{label:None,source:wgpu::ShaderSource::Wgsl(src.into())});
        let pipe = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor{label:None,layout:None,module:&module,entry_point:Some("main"),compilation_options:Default::default(),cache:None});
        let res0 = match name { n if n.starts_with("texture") || n == "storage-texture" => { let v = tex.create_view(&Default::default()); let bg = device.create_bind_group(&wgpu::BindGroupDescriptor{label:None,layout:&pipe.get_bind_group_layout(0),entries:&[wgpu::BindGroupEntry{binding:0,resource:wgpu::BindingResource::TextureView(&v)},wgpu::BindGroupEntry{binding:1,resource:out.as_entire_binding()}]}); bg }
            "uniform" => device.create_bind_group(&wgpu::BindGroupDescriptor{label:None,layout:&pipe.get_bind_group_layout(0),entries:&[wgpu::BindGroupEntry{binding:0,resource:ubuf.as_entire_binding()},wgpu::BindGroupEntry{binding:1,resource:out.as_entire_binding()}]}),
            _ => device.create_bind_group(&wgpu::BindGroupDescriptor{label:None,layout:&pipe.get_bind_group_layout(0),entries:&[wgpu::BindGroupEntry{binding:0,resource:buf.as_entire_binding()},wgpu::BindGroupEntry{binding:1,resource:out.as_entire_binding()}]}) };
        for rep in 0..3 {
            let t = Instant::now();
            let mut enc = device.create_command_encoder(&Default::default());
            { let mut p = enc.begin_compute_pass(&Default::default()); p.set_pipeline(&pipe); p.set_bind_group(0, &res0, &[]); p.dispatch_workgroups(64, 64, 1); }
            queue.submit([enc.finish()]);
            device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
            let dt = t.elapsed().as_secs_f64();
            let loads = 512.0*512.0*64.0;
            if rep > 0 { println!("{name:18} {:.1} ms  {:.1} M loads/s", dt*1e3, loads/dt/1e6); }
        }
    }
}
