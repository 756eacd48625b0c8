#!/usr/bin/python3
# The arithmetic of a generate run's networks at the official settings, counted from the layer shapes
# (FLOP = 2 x multiply-adds; norms, activations, softmax and copies not counted): the numbers of the
# roofline table in docs/networks.md ("Roofline"). SD 1.x UNets (block channels 320/640/1280/1280, two
# layers a block, one transformer block a level), the tile ControlNet and RRDBNet x4 as configured in
# tests/data/nn/manifests. The check line reproduces the 1.41 TFLOP that docs/networks.md gives for
# bench_unet's batch 8 at 32x32. Standard library only:
#     python3 bench/flop_count.py
CHANNELS = [320, 640, 1280, 1280]
CONTEXT_DIM = 768
TERA = 1e12


class Count:
    def __init__(self):
        self.conv = self.linear = self.attention = 0.0
        self.before_last_record = None  # a reference pass's arithmetic up to its last recorded attn1 input

    def total(self):
        return self.conv + self.linear + self.attention


def conv(c, cin, cout, side, kernel=3):
    c.conv += 2.0 * side * side * cin * cout * kernel * kernel


def resnet(c, cin, cout, side):
    conv(c, cin, cout, side)
    conv(c, cout, cout, side)
    if cin != cout:
        conv(c, cin, cout, side, 1)


def transformer(c, ch, side, context_len, views=1, ip_tokens=0, crosspond=False, last=False):
    n = side * side
    conv(c, ch, ch, side, 1)  # proj_in
    if last:
        c.before_last_record = c.total()  # attn1's input (after norm1) is what the reference records
    c.linear += 2.0 * 4 * n * ch * ch  # attn1: q, k, v, out
    c.attention += 2.0 * 2 * n * (n * views) * ch  # q.k^T and p.v, over the keys of all views
    if crosspond:
        c.linear += 2.0 * 2 * n * ch * ch  # reference attention: to_v, to_out of the recorded tokens
    c.linear += 2.0 * 2 * n * ch * ch + 2.0 * 2 * context_len * CONTEXT_DIM * ch  # attn2 projections
    c.attention += 2.0 * 2 * n * context_len * ch
    if ip_tokens:
        c.linear += 2.0 * 2 * ip_tokens * CONTEXT_DIM * ch
        c.attention += 2.0 * 2 * n * ip_tokens * ch
    c.linear += 2.0 * 12 * n * ch * ch  # feed-forward: GEGLU ch -> 2 x 4ch, then 4ch -> ch
    conv(c, ch, ch, side, 1)  # proj_out


def unet(side, in_channels=4, context_len=1, views=1, ip_tokens=0, crosspond=False, controlnet=False):
    """One sample's forward at side x side latents."""
    c = Count()
    t = dict(context_len=context_len, views=views, ip_tokens=ip_tokens, crosspond=crosspond)
    conv(c, in_channels, CHANNELS[0], side)
    skips, skip_sides = [CHANNELS[0]], [side]
    s, prev = side, CHANNELS[0]
    for i, ch in enumerate(CHANNELS):
        for _ in range(2):
            resnet(c, prev, ch, s)
            prev = ch
            if i < 3:
                transformer(c, ch, s, **t)
            skips.append(ch)
            skip_sides.append(s)
        if i < 3:
            conv(c, ch, ch, s // 2)  # downsampler
            s //= 2
            skips.append(ch)
            skip_sides.append(s)
    resnet(c, CHANNELS[3], CHANNELS[3], s)
    transformer(c, CHANNELS[3], s, **t)
    resnet(c, CHANNELS[3], CHANNELS[3], s)
    if controlnet:
        for ch, skip_side in zip(skips, skip_sides):
            conv(c, ch, ch, skip_side, 1)  # zero convolutions
        conv(c, CHANNELS[3], CHANNELS[3], s, 1)
        return c
    prev = CHANNELS[3]
    for i, ch in enumerate(reversed(CHANNELS)):
        for j in range(3):
            resnet(c, prev + skips.pop(), ch, s)
            prev = ch
            if i > 0:
                transformer(c, ch, s, last=(i == 3 and j == 2), **t)
        if i < 3:
            conv(c, ch, ch, s * 2)  # upsampler
            s *= 2
    conv(c, CHANNELS[0], 4, s)  # conv_out
    return c


def control_embedding(image_side):
    """The ControlNet's conditioning embedding of one control image (channels 16, 32, 96, 256 -> 320)."""
    c = Count()
    s = image_side
    conv(c, 3, 16, s)
    for cin, cout in [(16, 32), (32, 96), (96, 256)]:
        conv(c, cin, cin, s)
        s //= 2
        conv(c, cin, cout, s)
    conv(c, 256, 320, s)
    return c.total()


def rrdbnet_x4(side):
    """Real-ESRGAN x4plus (23 RRDB blocks, 64 channels, growth 32) on a side x side image."""
    rdb = 9 * (64 * 32 + 96 * 32 + 128 * 32 + 160 * 32 + 192 * 64)
    macs = 3 * 64 * 9 + 23 * 3 * rdb + 64 * 64 * 9  # conv_first, trunk, conv_body
    macs += 64 * 64 * 9 * 4 + 64 * 64 * 9 * 16 * 2 + 64 * 3 * 9 * 16  # up x2, up x4, conv_hr, conv_last
    return 2.0 * macs * side * side


def main():
    check = unet(32)
    print("check: UNet batch 8 at 32x32: %.2f TFLOP (convolutions %.2f, linear %.2f, attention products %.2f)"
          % (8 * check.total() / TERA, 8 * check.conv / TERA, 8 * check.linear / TERA, 8 * check.attention / TERA))

    reference, main_unet = unet(64), unet(64, crosspond=True)
    before = 8 * reference.total() + 8 * main_unet.total()  # 4 views x 2 guidance halves, each UNet
    # The unconditional half's reference pass once, and its crosspond term (to_v, to_out of the one
    # recorded sample) once for its four views.
    crosspond = main_unet.total() - reference.total()
    now = 5 * reference.before_last_record + 8 * main_unet.total() - 3 * crosspond
    print("normal step, 4 views at 64x64, both halves: reference pass %.1f GFLOP a sample (%.1f up to its last "
          "record), main UNet %.1f (its crosspond terms %.1f); step %.2f TFLOP before, %.2f now; 30 steps %.0f -> "
          "%.0f TFLOP"
          % (reference.total() / 1e9, reference.before_last_record / 1e9, main_unet.total() / 1e9, crosspond / 1e9,
             before / TERA, now / TERA, 30 * before / TERA, 30 * now / TERA))

    multiview = 8 * unet(32, in_channels=8, views=4).total()
    print("multi-view step, batch 8 at 32x32, attention over 4 views: %.2f TFLOP; 30 steps %.0f TFLOP"
          % (multiview / TERA, 30 * multiview / TERA))

    refine_unet = unet(128, context_len=77, ip_tokens=4).total()
    refine_controlnet = unet(128, context_len=77, controlnet=True).total()
    embedding = control_embedding(1024)
    step = 2 * (refine_unet + refine_controlnet)
    print("refine step, batch 2 at 128x128: UNet with IP-Adapter %.2f + ControlNet %.2f TFLOP a sample, control "
          "embedding %.3f a sample; 10 steps %.1f TFLOP with the embedding every step, %.1f with it once"
          % (refine_unet / TERA, refine_controlnet / TERA, embedding / TERA, 10 * (step + 2 * embedding) / TERA,
             (10 * step + 2 * embedding) / TERA))

    print("Real-ESRGAN x4 of a 512 px image: %.2f TFLOP" % (rrdbnet_x4(512) / TERA))


if __name__ == "__main__":
    main()
