// Fresnel and refraction for smooth dielectrics.
#ifndef OPTICS_GLSL
#define OPTICS_GLSL

// Unpolarized Fresnel reflectance for light going from index n1 into n2, with cos_i = cos of the incidence
// angle (>= 0). Returns 1 for total internal reflection.
float fresnel_dielectric(float cos_i, float n1, float n2) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float eta = n1 / n2;
    float sin_t2 = eta * eta * (1.0 - cos_i * cos_i);
    if (sin_t2 >= 1.0) return 1.0;
    float cos_t = sqrt(1.0 - sin_t2);
    float rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    float rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    return 0.5 * (rs * rs + rp * rp);
}

// Refract unit direction d through a surface with unit normal n facing the incoming side (dot(d, n) < 0),
// eta = n_incident / n_transmitted. Returns false on total internal reflection.
bool refract_dir(vec3 d, vec3 n, float eta, out vec3 t) {
    float cos_i = -dot(d, n);
    float k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    if (k < 0.0) {
        t = reflect(d, n);
        return false;
    }
    t = normalize(eta * d + (eta * cos_i - sqrt(k)) * n);
    return true;
}

#endif
