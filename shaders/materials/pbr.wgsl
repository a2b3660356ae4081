// glTF's metallic-roughness material (twin: src/material/pbr.rs, whose comment gives the
// model): a mix of a coat over the base colour (shaders/coat.wgsl, not saturating), rough glass
// whose transmission it tints (dielectric.wgsl's functions) and a GGX metal with Schlick's
// Fresnel from F0 = base colour. Its base colour is GpuMaterial's albedo (albedo_at); its
// parameters: PbrParams, whose metallic and alpha its metallic-roughness image scales per hit
// (pbr_with_texel), and its clear coat, sheen and specular its layer and specular images
// (pbr_with_layers), both called by with_albedo_at in texture.wgsl.

// Light emitted on top of what it reflects (Pbr::emitted; GpuMaterial::emission*): its
// colour, times its image where it has one; from its front face unless two-sided.
fn pbr_emitted(m: Material, hit: Hit) -> vec3f {
    if !(hit.front_face || m.emission_two_sided != 0u) {
        return vec3f(0.0);
    }
//#if IMAGE_TEXTURE
    if m.emission_size.x > 0.0 {
        return image_at(m.emission_image, m.emission_size, m.emission_lookup, uv_at(m.emission_lookup, hit)) * m.emission;
    }
//#endif
    return m.emission;
}

// Its dielectric's Fresnel reshaping (PbrParams' specular_*, f0 the tint clamped to 1;
// NO_SPECULAR where it has none).
fn pbr_specular(p: PbrParams) -> vec4f {
    return vec4f(p.specular_factor, min(p.specular_tint, vec3f(1.0)));
}

fn schlick(f0: vec3f, cos: f32) -> vec3f {
    let x = pow(1.0 - clamp(cos, 0.0, 1.0), 5.0);
    return f0 + (vec3f(1.0) - f0) * x;
}

//#if DIELECTRIC
// The glass of the mix, as a dielectric's parameters (an index within INDEX_MATCHED of 1 is
// smooth: Dielectric::samples_lights).
fn pbr_glass(p: PbrParams) -> DielectricParams {
    return DielectricParams(p.ior, select(p.alpha, 0.0, abs(p.ior - 1.0) < INDEX_MATCHED));
}
//#endif

//#if METALLIC_ROUGHNESS || LAYER_IMAGES
// The GGX alpha of roughness: roughness^2, or 0 (smooth) below MIN_ALPHA (Coat::alpha_of).
fn roughness_alpha(roughness: f32) -> f32 {
    let alpha = roughness * roughness;
    return select(0.0, alpha, alpha >= MIN_ALPHA);
}
//#endif

//#if LAYER_IMAGES
// Its clear coat, sheen and specular scaled by texels of its layer and specular images
// (Pbr::layers_at): the layers' red channel scales the coat's factor, green its roughness, blue
// the sheen's roughness; the sheen image its colour; the specular image's red channel the
// specular factor, the specular colour image its colour's tint (and so the coat's K). A
// factor or colour taken to 0 is no coat or sheen there.
fn pbr_with_layers(m: Material, hit: Hit) -> Material {
    var p = pbr_params(m);
    if m.layer_image_size.x > 0.0 {
        let texel = image_at(m.layer_image, m.layer_image_size, m.layer_image_lookup, uv_at(m.layer_image_lookup, hit));
        p.clearcoat = p.clearcoat * texel.x;
        p.clearcoat_alpha = roughness_alpha(p.clearcoat_roughness * texel.y);
//#if SHEEN
        p.sheen_roughness = max(p.sheen_roughness_factor * texel.z, SHEEN_MIN_ROUGHNESS);
//#endif
    }
    if m.sheen_image_size.x > 0.0 {
        let texel = image_at(m.sheen_image, m.sheen_image_size, m.sheen_image_lookup, uv_at(m.sheen_image_lookup, hit));
        p.sheen_color = p.sheen_color * texel;
    }
//#if SPECULAR
    let specular_images = m.specular_image_size.x > 0.0 || m.specular_color_image_size.x > 0.0;
    if specular_images && p.specular_factor >= 0.0 {
        if m.specular_image_size.x > 0.0 {
            let texel = image_at(m.specular_image, m.specular_image_size, m.specular_image_lookup, uv_at(m.specular_image_lookup, hit));
            p.specular_factor = p.specular_factor * texel.x;
        }
        if m.specular_color_image_size.x > 0.0 {
            let texel = image_at(m.specular_color_image, m.specular_color_image_size, m.specular_color_image_lookup, uv_at(m.specular_color_image_lookup, hit));
            p.specular_tint = p.specular_tint * texel;
        }
        p.internal_reflectance = pbr_internal_reflectance(p);
    }
//#endif
    return pbr_with_params(m, p);
}

//#if SPECULAR
// The coat's K from its specular's mean opacity (SpecularFresnel::mean_opacity and
// Coat::with_specular): factor x (f0 + (1 - f0) x the shape's mean), f0 the largest channel's.
fn pbr_internal_reflectance(p: PbrParams) -> f32 {
    let f0 = min(max(max(p.specular_tint.x, p.specular_tint.y), p.specular_tint.z), 1.0);
    let mean = p.specular_factor * (f0 + (1.0 - f0) * p.specular_shape_mean);
    return 1.0 - (1.0 - mean) / (p.ior * p.ior);
}
//#endif
//#endif

//#if METALLIC_ROUGHNESS

// Its metallic and alpha scaled by a texel of its metallic-roughness image (Pbr::at).
fn pbr_with_texel(m: Material, texel: vec3f) -> Material {
    var p = pbr_params(m);
    p.metallic = p.metallic * texel.z;
    p.transmission = select(p.transmission, p.transmission * texel.x, (p.flags & PBR_TRANSMISSION_IN_RED) != 0u);
    p.alpha = roughness_alpha(p.roughness * texel.y);
    return pbr_with_params(m, p);
}
//#endif

fn pbr_samples_lights(m: Material) -> bool {
    return (pbr_params(m).flags & PBR_SAMPLES_LIGHTS) != 0u;
}

// The metal's BSDF x cos (xyz) and pdf (w) at (wo, wi), rough only.
fn pbr_metal(alpha: f32, base: vec3f, wo: vec3f, wi: vec3f, hit: Hit) -> vec4f {
    let frame = frame_of(hit.shading);
    let wo_local = to_local(frame, wo);
    let wi_local = to_local(frame, wi);
    if !(alpha > 0.0) || !(wo_local.z > MIN_COSINE && wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
        return vec4f(0.0);
    }
    let mf = normalize(wo_local + wi_local);
    let f = schlick(base, dot(wo_local, mf)) * (ggx_d(alpha, mf) * ggx_g2(alpha, wo_local, wi_local) / (4.0 * wo_local.z));
    return vec4f(f, ggx_reflection_pdf(alpha, wo_local, mf));
}

fn pbr_eval_mix(m: Material, p: PbrParams, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let w_coat = (1.0 - p.metallic) * (1.0 - p.transmission);
    let w_glass = (1.0 - p.metallic) * p.transmission;
    let w_metal = p.metallic;
    let base = albedo_at(m, hit);
    var f = vec3f(0.0);
    if w_coat > 0.0 {
        f += w_coat * coat_eval(base, p.ior, p.alpha, p.internal_reflectance, false, NO_COAT_TABLE, pbr_specular(p), wo, wi, hit);
    }
//#if DIELECTRIC
    if w_glass > 0.0 {
        let tint = select(vec3f(1.0), base, dot(wi, hit.shading) < 0.0);
        f += w_glass * tint * glass_eval(pbr_glass(p), pbr_specular(p), wo, wi, hit);
    }
//#endif
    if w_metal > 0.0 {
        f += w_metal * pbr_metal(p.alpha, base, wo, wi, hit).xyz;
    }
    return f;
}

fn pbr_pdf_mix(m: Material, p: PbrParams, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    let w_coat = (1.0 - p.metallic) * (1.0 - p.transmission);
    let w_glass = (1.0 - p.metallic) * p.transmission;
    let w_metal = p.metallic;
    let base = albedo_at(m, hit);
    var pdf = 0.0;
    if w_coat > 0.0 {
        pdf += w_coat * coat_pdf(base, p.ior, p.alpha, NO_COAT_TABLE, pbr_specular(p), wo, wi, hit);
    }
//#if DIELECTRIC
    if w_glass > 0.0 {
        pdf += w_glass * glass_pdf(pbr_glass(p), pbr_specular(p), wo, wi, hit);
    }
//#endif
    if w_metal > 0.0 {
        pdf += w_metal * pbr_metal(p.alpha, base, wo, wi, hit).w;
    }
    return pdf;
}

// BSDF x cos over its non-delta lobes: the clear coat's, and the mix's seen through it.
// The sheen's BSDF x cos and the mix's seen through it.
fn pbr_eval_below(m: Material, p: PbrParams, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let mix = pbr_eval_mix(m, p, wo, wi, hit);
//#if SHEEN
    if any(p.sheen_color > vec3f(0.0)) {
        return sheen_eval(p.sheen_color, p.sheen_roughness, wo, wi, hit) + mix * sheen_through(m.sheen_table, p.sheen_color, p.sheen_roughness, wo, hit);
    }
//#endif
    return mix;
}

// The density of pbr_sample_below's non-delta directions.
fn pbr_pdf_below(m: Material, p: PbrParams, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    let mix = pbr_pdf_mix(m, p, wo, wi, hit);
//#if SHEEN
    if any(p.sheen_color > vec3f(0.0)) {
        let chance = sheen_reflectance(m.sheen_table, p.sheen_color, p.sheen_roughness, dot(wo, hit.shading));
        return chance * cosine_pdf(hit, wi) + (1.0 - chance) * mix;
    }
//#endif
    return mix;
}

// A direction from below any clear coat: the sheen's (picked with its reflectance at wo;
// cosine-distributed), else the mix's; a delta one weighed, any other for pbr_sample to weigh.
fn pbr_sample_below(m: Material, p: PbrParams, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
//#if SHEEN
    if any(p.sheen_color > vec3f(0.0)) {
        let chance = sheen_reflectance(m.sheen_table, p.sheen_color, p.sheen_roughness, dot(wo, hit.shading));
        if sampler_next(sampler) < chance {
            let u1 = sampler_next(sampler);
            let u2 = sampler_next(sampler);
            return BsdfSample(vec3f(0.0), cosine_direction(hit.shading, u1, u2), 0.0, LOBE_REFLECTION | LOBE_GLOSSY);
        }
        // A delta of the mix keeps its weight: what shows through the sheen over the chance
        // of not picking it, 1.
        return pbr_sample_mix(m, p, wo, hit, sampler);
    }
//#endif
    return pbr_sample_mix(m, p, wo, hit, sampler);
}

fn pbr_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {
    let p = pbr_params(m);
    let mix = pbr_eval_below(m, p, wo, wi, hit);
//#if CLEARCOAT
    if p.clearcoat > 0.0 {
        return mix * clearcoat_through(p.clearcoat, wo, hit) + vec3f(clearcoat_lobe(p.clearcoat, p.clearcoat_alpha, wo, wi, hit).x);
    }
//#endif
    return mix;
}

// The density of pbr_sample over its non-delta lobes.
fn pbr_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {
    let p = pbr_params(m);
    let mix = pbr_pdf_below(m, p, wo, wi, hit);
//#if CLEARCOAT
    if p.clearcoat > 0.0 {
        let chance = clearcoat_reflectance(p.clearcoat, dot(wo, hit.coat));
        return chance * clearcoat_lobe(p.clearcoat, p.clearcoat_alpha, wo, wi, hit).y + (1.0 - chance) * mix;
    }
//#endif
    return mix;
}

// Under a clear coat, one number picks the coat (with its reflectance at wo) or the mix below;
// the mix's deltas keep their weight, and any other direction is weighed by the whole BSDF over
// the whole density.
fn pbr_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    let p = pbr_params(m);
    var out: BsdfSample;
//#if CLEARCOAT
    if p.clearcoat > 0.0 {
        let chance = clearcoat_reflectance(p.clearcoat, dot(wo, hit.coat));
        if sampler_next(sampler) < chance {
            let u1 = sampler_next(sampler);
            let u2 = sampler_next(sampler);
            out = clearcoat_sample(p.clearcoat_alpha, wo, hit, u1, u2);
        } else {
            // A delta below keeps its weight: what crosses the coat over the chance of not
            // sampling it, 1.
            out = pbr_sample_below(m, p, wo, hit, sampler);
        }
    } else {
        out = pbr_sample_below(m, p, wo, hit, sampler);
    }
//#else
    out = pbr_sample_below(m, p, wo, hit, sampler);
//#endif
    if out.lobe == 0u || (out.lobe & LOBE_DELTA) != 0u {
        return out;
    }
    let pdf = pbr_pdf(m, wo, out.wi, hit);
    if !(pdf > 0.0) {
        out.lobe = 0u;
        return out;
    }
    out.weight = pbr_eval(m, wo, out.wi, hit) / pdf;
    out.pdf = pdf;
    return out;
}

// A direction from the mix below any clear coat: a delta one weighed (its component's weight
// alone), any other for pbr_sample to weigh.
fn pbr_sample_mix(m: Material, p: PbrParams, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {
    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);
    let w_coat = (1.0 - p.metallic) * (1.0 - p.transmission);
    let w_glass = (1.0 - p.metallic) * p.transmission;
    let base = albedo_at(m, hit);
    let u = sampler_next(sampler);
    if u < w_coat {
        let v = sampler_next(sampler);
        let u1 = sampler_next(sampler);
        let u2 = sampler_next(sampler);
        out = coat_sample(base, p.ior, p.alpha, p.internal_reflectance, false, NO_COAT_TABLE, pbr_specular(p), wo, hit, v, u1, u2);
    } else if u < w_coat + w_glass {
//#if DIELECTRIC
        out = glass_sample(pbr_glass(p), pbr_specular(p), wo, hit, sampler);
        // A direction within rounding of where the glass's own density vanishes: not one for
        // the other components' densities to weigh.
        if out.lobe != 0u && (out.lobe & LOBE_DELTA) == 0u && !(glass_pdf(pbr_glass(p), pbr_specular(p), wo, out.wi, hit) > 0.0) {
            out.lobe = 0u;
        }
        out.weight *= select(vec3f(1.0), base, (out.lobe & LOBE_TRANSMISSION) != 0u);
//#endif
    } else {
        let u1 = sampler_next(sampler);
        let u2 = sampler_next(sampler);
        let frame = frame_of(hit.shading);
        let wo_local = to_local(frame, wo);
        if !(wo_local.z > MIN_COSINE) {
            return out;
        }
        if !(p.alpha > 0.0) {
            out.wi = reflect_dir(-wo, hit.shading);
            out.weight = schlick(base, wo_local.z);
            out.lobe = select(0u, LOBE_REFLECTION | LOBE_DELTA, !below_surface(hit, out.wi));
            return out;
        }
        let mf = ggx_sample_visible(p.alpha, wo_local, u1, u2);
        let wi_local = reflect_dir(-wo_local, mf);
        let wi = to_world(frame, wi_local);
        // Below the surface the metal's own density is lost mass: the path ends.
        if !(wi_local.z > MIN_COSINE) || below_surface(hit, wi) {
            return out;
        }
        out.wi = wi;
        out.lobe = LOBE_REFLECTION | LOBE_GLOSSY;
    }
    return out;
}
