//! `specula view SCENE`: the scene in a window, rendered every frame by the same
//! `Renderer` as every other command, through the host-image path an engine takes
//! (`Renderer::record_into` into the swapchain image). A fly camera (WASD, right-drag to
//! look) and an orbit mode (O; drag and wheel), the glTF animations playing (Space pauses),
//! an overlay (F1) with the plan, each object's method, the knobs and the per-pass GPU
//! timings, and a screenshot key (F12) that writes PNG + EXR with the `specula render`
//! arguments that reproduce it. `--script FILE` plays input frame by frame (`script`), for
//! tests under `xvfb-run` and reproducible demos.

mod camera;
mod present;
mod script;
mod ui;

use std::ffi::CStr;
use std::path::{Path, PathBuf};
use std::time::Instant;

use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use specula::error::VkCall;
use specula::plan::{Choice, Method};
use specula::quality::{Quality, KNOBS};
use specula::scene::Scene;
use specula::vk::{Context, DeviceOptions, PassTiming};
use specula::Renderer;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::args::{prepare, write_image, Job, RenderArgs};
use camera::{Controller, Mode, Move};
use script::{Action, Script, SCRIPT_DT};

#[derive(clap::Args)]
pub struct ViewArgs {
    /// glTF scene (.gltf/.glb) or builtin:NAME.
    scene: PathBuf,
    /// auto, or one GPU method for every specular object.
    #[arg(long, default_value = "auto")]
    method: String,
    /// NAME=METHOD for one object (repeatable).
    #[arg(long = "object")]
    objects: Vec<String>,
    /// The window's (and the frame's) size WIDTHxHEIGHT; resizing the window renders at the new size.
    #[arg(long, default_value = "640x480")]
    size: String,
    /// Knob KEY=VALUE (repeatable).
    #[arg(long = "quality", short = 'q')]
    quality: Vec<String>,
    /// Environment map (.hdr/.exr equirectangular).
    #[arg(long)]
    env: Option<PathBuf>,
    #[arg(long)]
    camera_pos: Option<String>,
    #[arg(long)]
    camera_target: Option<String>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    fov: Option<f32>,
    /// The Khronos validation layer on; the viewer exits 1 if it reported errors.
    #[arg(long)]
    validate: bool,
    /// Substring of the device name.
    #[arg(long)]
    device: Option<String>,
    /// Input to play, frame by frame (fixed 1/30 s steps).
    #[arg(long)]
    script: Option<PathBuf>,
    /// Close after this many frames.
    #[arg(long)]
    frames: Option<u64>,
    /// Where screenshots go (created).
    #[arg(long, default_value = "screenshots")]
    screenshots: PathBuf,
}

pub fn run(a: &ViewArgs) -> specula::Result<()> {
    let render_args = RenderArgs {
        scene: a.scene.clone(),
        method: a.method.clone(),
        objects: a.objects.clone(),
        size: a.size.clone(),
        quality: a.quality.clone(),
        env: a.env.clone(),
        camera_pos: a.camera_pos.clone(),
        camera_target: a.camera_target.clone(),
        fov: a.fov,
        time: None,
        validate: a.validate,
        device: a.device.clone(),
        warmup: 0,
        frames: 1,
    };
    let mut job = prepare(&render_args)?;
    if job.cpu_method().is_some() {
        return Err(specula::Error::invalid("--method", "the viewer renders on the GPU: the reference renders with `specula render`"));
    }
    // A view over time: maps are regenerated when what they see changed, unless asked otherwise.
    if !a.quality.iter().any(|q| q.trim_start().starts_with(specula::quality::FrameKnobs::map_updates)) {
        job.quality.frame.map_updates_always = false;
    }
    let script = a.script.as_deref().map(Script::load).transpose()?;
    let event_loop = EventLoop::new().map_err(|e| {
        specula::Error::invalid("window", format!("cannot open one ({e}): the viewer needs an X11 display (DISPLAY), e.g. under xvfb-run"))
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut scene = job.scene.clone();
    if scene.animation.is_some() {
        scene.set_time(0.0)?;
    }
    let mut app = App {
        ctl: Controller::new(&scene),
        scene,
        job,
        args: render_args,
        screenshots: a.screenshots.clone(),
        script,
        max_frames: a.frames,
        frame: 0,
        time: 0.0,
        paused: false,
        last: Instant::now(),
        fps: 0.0,
        messages: Vec::new(),
        overlay: ui::Overlay::default(),
        pending: Vec::new(),
        mouse: Mouse::default(),
        error: None,
        gpu: None,
    };
    let run = event_loop.run_app(&mut app);
    let validation =
        app.gpu.as_ref().map(|g| (g.ctx.validation.error_count(), g.ctx.validation.warning_count(), g.ctx.validation.error_messages()));
    app.shutdown();
    run.map_err(|e| specula::Error::invalid("window", format!("its event loop: {e}")))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    println!("viewed {} frames", app.frame);
    if let (true, Some((errors, warnings, messages))) = (a.validate, validation) {
        println!("validation: {errors} error(s), {warnings} warning(s)");
        if errors > 0 {
            for m in messages {
                eprintln!("specula view: {m}");
            }
            return Err(specula::Error::Validation(errors));
        }
    }
    Ok(())
}

#[derive(Default)]
struct Mouse {
    at: Option<(f64, f64)>,
    look: bool,
}

/// What lives on the device, created once the window exists; torn down in reverse.
struct Gpu {
    window: Window,
    ctx: Context,
    present: present::Presenter,
    egui_ctx: egui::Context,
    egui_state: egui_winit::State,
    egui_renderer: Option<egui_ash_renderer::Renderer>,
    renderer: Option<Renderer>,
    /// What `auto` predicts with: this device's unit costs, found the first time `auto` is
    /// asked for (a fixed method needs none, and a first calibration takes minutes on a CPU
    /// device).
    target: std::sync::OnceLock<Option<specula::plan::predict::Target>>,
    /// Overlay textures to free once the frame that last drew with them has completed.
    free_later: Vec<egui::TextureId>,
    timings: Vec<PassTiming>,
}

struct App {
    job: Job,
    /// The scene as posed this frame, with the viewer's camera.
    scene: Scene,
    args: RenderArgs,
    ctl: Controller,
    screenshots: PathBuf,
    script: Option<Script>,
    max_frames: Option<u64>,
    frame: u64,
    time: f32,
    paused: bool,
    last: Instant,
    fps: f64,
    messages: Vec<String>,
    overlay: ui::Overlay,
    /// Actions from the window's keys and the overlay, applied at the next frame.
    pending: Vec<Action>,
    mouse: Mouse,
    error: Option<specula::Error>,
    gpu: Option<Gpu>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.gpu.is_none() {
            if let Err(e) = self.start(el) {
                self.error = Some(e);
                el.exit();
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gpu) = self.gpu.as_mut() else { return };
        let consumed = gpu.egui_state.on_window_event(&gpu.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(_) => gpu.present.out_of_date = true,
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame(el) {
                    self.error = Some(e);
                    el.exit();
                }
            }
            WindowEvent::KeyboardInput { event, .. } if !consumed || event.state == ElementState::Released => {
                let PhysicalKey::Code(code) = event.physical_key else { return };
                let down = event.state == ElementState::Pressed;
                if let Some(m) = key_move(code) {
                    self.pending.push(Action::Key(m, down));
                } else if down && !event.repeat {
                    match code {
                        KeyCode::Escape => el.exit(),
                        KeyCode::F1 => self.overlay.hidden = !self.overlay.hidden,
                        KeyCode::KeyO => self.pending.push(Action::Orbit),
                        KeyCode::Space => self.pending.push(Action::Pause),
                        KeyCode::F12 | KeyCode::KeyP => self.pending.push(Action::Screenshot(format!("frame{:06}", self.frame))),
                        KeyCode::KeyM => {
                            let next = next_choice(self.job.choices.method);
                            self.pending.push(Action::Method(None, next.to_string()));
                        }
                        _ => {}
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } if !consumed || state == ElementState::Released => {
                let look = if self.ctl.mode == Mode::Fly { MouseButton::Right } else { MouseButton::Left };
                if button == look {
                    self.mouse.look = state == ElementState::Pressed;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y))) = (self.mouse.look, self.mouse.at) {
                    self.pending.push(Action::Look((position.x - x) as f32, (position.y - y) as f32));
                }
                self.mouse.at = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.pending.push(Action::Wheel(steps));
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _el: &ActiveEventLoop) {
        if let Some(g) = &self.gpu {
            g.window.request_redraw();
        }
    }
}

fn key_move(code: KeyCode) -> Option<Move> {
    Some(match code {
        KeyCode::KeyW => Move::Forward,
        KeyCode::KeyS => Move::Back,
        KeyCode::KeyA => Move::Left,
        KeyCode::KeyD => Move::Right,
        KeyCode::KeyE => Move::Up,
        KeyCode::KeyQ => Move::Down,
        KeyCode::ShiftLeft | KeyCode::ShiftRight => Move::Fast,
        _ => return None,
    })
}

/// The whole-scene choice after `c`: auto, then every GPU method in the registry's order.
fn next_choice(c: Choice) -> &'static str {
    let names: Vec<&'static str> = std::iter::once("auto").chain(Method::ALL.iter().filter(|m| m.is_gpu()).map(|m| m.name())).collect();
    let at = names.iter().position(|n| *n == c.name()).unwrap_or(0);
    names[(at + 1) % names.len()]
}

impl App {
    /// The window, the device with the window's extensions, the swapchain, the overlay and
    /// the first renderer.
    fn start(&mut self, el: &ActiveEventLoop) -> specula::Result<()> {
        let (w, h) = (self.job.width, self.job.height);
        let title = format!("specula — {}", self.args.scene.display());
        let attrs = Window::default_attributes().with_title(title).with_inner_size(winit::dpi::PhysicalSize::new(w, h));
        let window = el.create_window(attrs).map_err(|e| specula::Error::invalid("window", format!("cannot create one: {e}")))?;
        let display = window.display_handle().map_err(|e| specula::Error::invalid("window", format!("its display: {e}")))?.as_raw();
        let handle = window.window_handle().map_err(|e| specula::Error::invalid("window", format!("its handle: {e}")))?.as_raw();
        let instance_extensions = ash_window::enumerate_required_extensions(display)
            .map_err(|e| specula::Error::Unsupported(format!("no Vulkan surface for this window system: {e}")))?
            .iter()
            // SAFETY: ash-window returns pointers to its static NUL-terminated extension names.
            .map(|&p| unsafe { CStr::from_ptr(p) }.to_owned())
            .collect();
        let ctx = Context::new(&DeviceOptions {
            validation: self.args.validate,
            device_filter: self.args.device.clone(),
            instance_extensions,
            device_extensions: vec![ash::khr::swapchain::NAME.to_owned()],
            ..Default::default()
        })?;
        // SAFETY: the handles are the live window's; the surface is destroyed (Presenter::
        // destroy) before the window and the instance.
        let surface =
            unsafe { ash_window::create_surface(&ctx.entry, &ctx.instance, display, handle, None) }.call("vkCreate*SurfaceKHR")?;
        let size = window.inner_size();
        let present = present::Presenter::new(&ctx, surface, (size.width.max(1), size.height.max(1)))?;
        let egui_ctx = egui::Context::default();
        let egui_state =
            egui_winit::State::new(egui_ctx.clone(), egui::ViewportId::ROOT, &window, Some(window.scale_factor() as f32), None, None);
        let egui_renderer = egui_ash_renderer::Renderer::with_default_allocator(
            &ctx.instance,
            ctx.physical,
            ctx.device.clone(),
            egui_ash_renderer::DynamicRendering { color_attachment_format: present.format, depth_attachment_format: None },
            egui_ash_renderer::Options { in_flight_frames: 1, enable_depth_test: false, enable_depth_write: false, srgb_framebuffer: true },
        )
        .map_err(|e| specula::Error::invalid("overlay", e.to_string()))?;
        println!("viewing {} on {} ({})", self.args.scene.display(), ctx.device_name, ctx.driver_info);
        self.gpu = Some(Gpu {
            window,
            ctx,
            present,
            egui_ctx,
            egui_state,
            egui_renderer: Some(egui_renderer),
            renderer: None,
            target: std::sync::OnceLock::new(),
            free_later: Vec::new(),
            timings: Vec::new(),
        });
        // The first renderer now: a screenshot on the first frame shows the first view.
        self.update_renderer()
    }

    /// A renderer for the scene as it is now, at the swapchain's size, with these choices
    /// and knobs; the old one stays until this one exists.
    fn make_renderer(&self, choices: &specula::plan::Choices, quality: &Quality) -> specula::Result<Renderer> {
        let gpu = self.gpu.as_ref().expect("the device exists while frames are drawn");
        let size = (gpu.present.extent.width, gpu.present.extent.height);
        let target = if choices.method == Choice::Auto {
            let found = gpu.target.get_or_init(|| {
                eprintln!(
                    "specula view: auto predicts with this device's unit costs: read from the cache, or measured now once \
                     (seconds on a GPU, about three minutes on lavapipe)"
                );
                specula::target_for(&gpu.ctx, size)
            });
            found.clone().or_else(specula::plan::predict::Target::nominal).map(|t| specula::plan::predict::Target { size, ..t })
        } else {
            None
        };
        let plan = specula::plan::plan_for(&self.scene, choices, quality, target.as_ref())?;
        Renderer::new(&gpu.ctx, &self.scene, plan, size.0, size.1)
    }

    fn replace_renderer(&mut self, r: Renderer) {
        let gpu = self.gpu.as_mut().expect("the device exists while frames are drawn");
        if let Some(mut old) = gpu.renderer.replace(r) {
            let _ = gpu.ctx.wait_idle();
            old.destroy(&gpu.ctx);
        }
        gpu.timings.clear();
    }

    fn say(&mut self, m: String) {
        eprintln!("specula view: {m}");
        self.messages.push(m);
        if self.messages.len() > 32 {
            self.messages.remove(0);
        }
    }

    /// Applies one action from the window, the overlay or the script. A method or knob the
    /// planner or the renderer refuses is reported and changes nothing.
    fn apply(&mut self, a: Action) -> specula::Result<()> {
        match a {
            Action::Key(m, down) => self.ctl.hold(m, down),
            Action::Look(dx, dy) => self.ctl.turn(dx, dy),
            Action::Orbit => self.ctl.toggle_mode(),
            Action::Wheel(s) => self.ctl.wheel(s),
            Action::Pause => self.paused = !self.paused,
            Action::Resize(w, h) => {
                // The window system answers with a Resized event (or not at all, where a
                // window manager keeps the size); the swapchain and the renderer follow it.
                let gpu = self.gpu.as_mut().expect("the device exists while frames are drawn");
                if let Some(now) = gpu.window.request_inner_size(winit::dpi::PhysicalSize::new(w, h)) {
                    if (now.width, now.height) == (w, h) {
                        gpu.present.out_of_date = true;
                    }
                }
            }
            Action::Method(object, name) => {
                let mut choices = self.job.choices.clone();
                let what = object.clone().unwrap_or_else(|| "the scene".into());
                let parsed = match &object {
                    None => Choice::parse(&name).map(|c| choices.method = c),
                    Some(o) => crate::args::parse_object(&format!("{o}={name}")).map(|(o, m)| {
                        choices.objects.retain(|(n, _)| *n != o);
                        choices.objects.push((o, m));
                    }),
                };
                match parsed.and_then(|()| self.make_renderer(&choices, &self.job.quality)) {
                    Ok(r) => {
                        self.job.choices = choices;
                        self.replace_renderer(r);
                        self.say(format!("{what}: {name}"));
                    }
                    Err(e) => self.say(format!("{name} for {what} refused, nothing changed: {e}")),
                }
            }
            Action::Knob(pair) => {
                let mut quality = self.job.quality.clone();
                match quality.set_pair(&pair).and_then(|()| self.make_renderer(&self.job.choices, &quality)) {
                    Ok(r) => {
                        self.job.quality = quality;
                        self.replace_renderer(r);
                        self.say(format!("knob {pair}"));
                    }
                    Err(e) => self.say(format!("knob {pair} refused, nothing changed: {e}")),
                }
            }
            Action::Screenshot(name) => self.screenshot(&name)?,
            Action::Quit => {}
        }
        Ok(())
    }

    /// The current view rendered as `specula render` renders it (a frame submitted and read
    /// back), written as NAME.png + NAME.exr, with NAME.txt holding the command line that
    /// renders it again.
    fn screenshot(&mut self, name: &str) -> specula::Result<()> {
        let gpu = self.gpu.as_mut().expect("the device exists while frames are drawn");
        let Some(r) = gpu.renderer.as_mut() else { return Ok(()) };
        gpu.ctx.wait_idle()?;
        let f = r.render(&gpu.ctx)?;
        std::fs::create_dir_all(&self.screenshots).map_err(|e| specula::Error::io(&self.screenshots, e))?;
        let stem = self.screenshots.join(name);
        write_image(&stem.with_extension("png"), &f.image)?;
        write_image(&stem.with_extension("exr"), &f.image)?;
        let command = self.render_command(f.image.width, f.image.height);
        specula::output::write_file(&stem.with_extension("txt"), format!("{command}\n").as_bytes())?;
        self.say(format!("wrote {}.png and .exr; again with: {command}", stem.display()));
        Ok(())
    }

    /// `specula render` arguments for what the window shows now.
    fn render_command(&self, w: u32, h: u32) -> String {
        let mut s = format!("specula render {} --size {w}x{h} --method {}", quote(&self.args.scene), self.job.choices.method.name());
        for (o, m) in &self.job.choices.objects {
            s += &format!(" --object {}", quote(Path::new(&format!("{o}={}", m.name()))));
        }
        if let Some(env) = &self.args.env {
            s += &format!(" --env {}", quote(env));
        }
        // The knobs that differ from what `specula render` starts from.
        let mut base = Quality::default();
        base.frame.map_updates_always = true;
        for k in KNOBS {
            let v = self.job.quality.get(k.name);
            if v != base.get(k.name) && k.name != specula::quality::FrameKnobs::map_updates {
                s += &format!(" -q {}={v}", k.name);
            }
        }
        if self.scene.animation.is_some() {
            s += &format!(" --time={}", self.time);
        }
        if self.ctl.moved {
            s += &format!(" {}", self.ctl.args());
        } else if let Some(p) = &self.args.camera_pos {
            s += &format!(" --camera-pos={p}");
            if let Some(t) = &self.args.camera_target {
                s += &format!(" --camera-target={t}");
            }
            if let Some(f) = self.args.fov {
                s += &format!(" --fov={f}");
            }
        }
        s + " --out OUT.exr"
    }

    /// One frame: input, animation, updates, the renderer's frame into the swapchain image,
    /// the overlay on top, present.
    fn frame(&mut self, el: &ActiveEventLoop) -> specula::Result<()> {
        {
            let gpu = self.gpu.as_mut().expect("the device exists while frames are drawn");
            gpu.present.wait(&gpu.ctx)?;
            let frees = std::mem::take(&mut gpu.free_later);
            if let Some(er) = gpu.egui_renderer.as_mut() {
                er.free_textures(&frees).map_err(|e| specula::Error::invalid("overlay", e.to_string()))?;
            }
            if gpu.present.out_of_date {
                let s = gpu.window.inner_size();
                gpu.present.recreate(&gpu.ctx, (s.width, s.height))?;
            }
            if gpu.present.extent.width == 0 || gpu.present.extent.height == 0 {
                return Ok(()); // minimised
            }
        }
        // Time and input: a script steps by a fixed 1/30 s and plays its actions first.
        let now = Instant::now();
        let wall = now.duration_since(self.last).as_secs_f64();
        self.last = now;
        self.fps = if self.fps == 0.0 { 1.0 / wall.max(1e-6) } else { 0.9 * self.fps + 0.1 / wall.max(1e-6) };
        let dt = if self.script.is_some() { SCRIPT_DT } else { (wall as f32).min(0.1) };
        let mut actions: Vec<Action> = self.script.as_ref().map(|s| s.at(self.frame).cloned().collect()).unwrap_or_default();
        actions.append(&mut self.pending);
        let mut quit = false;
        for a in actions {
            quit |= a == Action::Quit;
            self.apply(a)?;
        }
        self.ctl.step(dt);
        if self.scene.animation.is_some() && !self.paused {
            self.time += dt;
            self.scene.set_time(self.time)?;
        }
        if self.ctl.moved {
            self.scene.camera = Some(self.ctl.camera()?);
        }
        self.update_renderer()?;

        let gpu = self.gpu.as_mut().expect("the device exists while frames are drawn");
        if let Some(r) = gpu.renderer.as_mut() {
            gpu.timings = r.last_timings(&gpu.ctx)?.to_vec();
        }
        let Some(target) = gpu.present.acquire()? else { return Ok(()) };
        // The overlay's shapes and textures for this frame.
        let raw = gpu.egui_state.take_egui_input(&gpu.window);
        let camera_args = if self.ctl.moved { self.ctl.args() } else { "the scene's camera".to_string() };
        let plan = &gpu.renderer.as_ref().expect("a renderer exists after update_renderer").plan;
        let shown = ui::Shown {
            device: &gpu.ctx.device_name,
            size: (gpu.present.extent.width, gpu.present.extent.height),
            fps: self.fps,
            timings: &gpu.timings,
            plan,
            choice: self.job.choices.method,
            quality: &self.job.quality,
            messages: &self.messages,
            mode: self.ctl.mode,
            paused: self.scene.animation.as_ref().map(|_| self.paused),
            camera_args: &camera_args,
        };
        let overlay = &mut self.overlay;
        let mut asked = Vec::new();
        let out = gpu.egui_ctx.run(raw, |c| asked = overlay.draw(c, &shown));
        self.pending.extend(asked);
        gpu.egui_state.handle_platform_output(&gpu.window, out.platform_output);
        let primitives = gpu.egui_ctx.tessellate(out.shapes, out.pixels_per_point);
        let queue = gpu.ctx.queue.ok_or_else(|| specula::Error::invalid("window", "the viewer's context has no queue"))?;
        let er = gpu.egui_renderer.as_mut().expect("the overlay renderer lives until shutdown");
        er.set_textures(queue, gpu.present.pool(), &out.textures_delta.set)
            .map_err(|e| specula::Error::invalid("overlay", e.to_string()))?;
        gpu.free_later = out.textures_delta.free;

        let cmd = gpu.present.begin(&gpu.ctx)?;
        let mut host = gpu.present.host_image(&target);
        gpu.renderer.as_mut().expect("a renderer exists after update_renderer").record_into(
            &gpu.ctx,
            cmd,
            &mut host,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        )?;
        let extent = gpu.present.extent;
        let attachment = [vk::RenderingAttachmentInfo::default()
            .image_view(target.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let rendering = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&attachment);
        unsafe { gpu.ctx.device.cmd_begin_rendering(cmd, &rendering) };
        er.cmd_draw(cmd, extent, out.pixels_per_point, &primitives).map_err(|e| specula::Error::invalid("overlay", e.to_string()))?;
        unsafe { gpu.ctx.device.cmd_end_rendering(cmd) };
        gpu.present.submit_and_present(&gpu.ctx, &target)?;
        self.frame += 1;
        if quit || self.max_frames.is_some_and(|n| self.frame >= n) {
            el.exit();
        }
        Ok(())
    }

    /// Hands the renderer this frame's scene; a first renderer, one at a new window size, or
    /// one for a pose that changed the plan's structure (as `specula animate` does).
    fn update_renderer(&mut self) -> specula::Result<()> {
        let gpu = self.gpu.as_mut().expect("the device exists while frames are drawn");
        let size = (gpu.present.extent.width, gpu.present.extent.height);
        let why = match gpu.renderer.as_mut() {
            None => None,
            Some(r) if (r.width, r.height) != size => Some(format!("new size {}x{}", size.0, size.1)),
            Some(r) => r.update(&self.scene).err().map(|e| e.to_string()),
        };
        if gpu.renderer.is_none() || why.is_some() {
            let r = self.make_renderer(&self.job.choices, &self.job.quality)?;
            self.replace_renderer(r);
            if let Some(why) = why {
                self.say(format!("new renderer: {why}"));
            }
        }
        Ok(())
    }

    /// Destroys what lives on the device, in reverse order of creation.
    fn shutdown(&mut self) {
        if let Some(mut gpu) = self.gpu.take() {
            let _ = gpu.ctx.wait_idle();
            drop(gpu.egui_renderer.take());
            if let Some(mut r) = gpu.renderer.take() {
                r.destroy(&gpu.ctx);
            }
            gpu.present.destroy(&gpu.ctx);
            drop(gpu.ctx);
            drop(gpu.window);
        }
    }
}

impl Drop for App {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// A path or argument quoted for a POSIX shell where it needs it.
fn quote(p: &Path) -> String {
    let s = p.display().to_string();
    if s.chars().all(|c| c.is_ascii_alphanumeric() || "-_./:=+,".contains(c)) {
        s
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}
