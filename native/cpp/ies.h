// IES light profiles (the IES Texture node in a light's shader), as Cycles 5.0 evaluates them:
// a table of intensities over vertical angle (0 = straight down the light's -Z) and horizontal
// angle (0..2 pi), built by addon/lights/ies.py (Cycles' util/ies.cpp), looked up with Cycles'
// kernel_ies_interp (kernel/util/ies.h: bicubic, wrapping round the poles and past 360 degrees,
// 0 outside the table) in its float32 operations. A lamp record names its profile by an id
// (LampRecord::ies, 0 = none) in a registry whose tables live as long as a handle holds them
// (ies_register / ies_release: the Python IesProfile a render's lamps keep).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace dacrt {

struct IesTable {
    std::vector<float> h, v;  // angles in radians in the file's order (Cycles reads any)
    std::vector<float> I;     // I[ih * v.size() + iv]
};

// kernel_ies_interp: the profile's value at (h_angle, v_angle); 0 outside the table (a single
// angle on an axis: everywhere) and where Cycles' value is NaN or inf.
float ies_interp(const IesTable& t, float h_angle, float v_angle);

// svm_node_ies on a direction d in the light's object space (from the light toward the lit
// point; not normalised): v = acos(-z), h = atan2(x, y) + pi of d / |d|; 0 for d = 0.
float ies_direction(const IesTable& t, const float d[3]);

// The live profile with this id, or null (never registered, or released). Lock-free: render
// threads read while another thread registers or releases other profiles; a table is deleted
// only when its last reference goes, which its readers hold.
const IesTable* ies_table(int id);

// Registers a profile (checked: sizes, no axis of one NaN angle; else
// std::invalid_argument) and returns its id >= 1 holding one reference; an identical live table
// gets its id and one more reference. At most kIesMaxTables distinct tables live at once.
int ies_register(std::vector<float> h, std::vector<float> v, std::vector<float> I);

// Drops one reference of id; the last deletes the table and frees its slot. An id not live: no-op.
void ies_release(int id);

// Distinct tables alive now.
int ies_live();

constexpr int kIesMaxTables = 4096;

// Empty if id is 0 or live, else what is wrong (lamp_record_error).
std::string ies_id_error(float id);

// The factor of lamp profile id (registered, != 0) for a world direction from the light,
// through m3 (row-major world -> light object, as Cycles transforms the node's default Vector,
// Geometry Incoming, world to object as a normal). Out of line: lamps without a profile keep
// their code as it was.
float ies_lamp_factor(float id, const float m3[9], const float from_light[3]);

}  // namespace dacrt
