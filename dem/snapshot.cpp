#include "dem/snapshot.hpp"

#include <sstream>

#include "core/atomic_file.hpp"
#include "core/io/hdf5.hpp"
#include "core/table.hpp"

namespace tg::dem {

void write_snapshot(const Particles& p, const std::filesystem::path& path, const std::string& attributes_json) {
  Table t;
  const char* names[] = {"x_m", "y_m", "z_m", "r_m", "vx_m_s", "vy_m_s", "vz_m_s", "wx_rad_s", "wy_rad_s", "wz_rad_s"};
  const std::vector<double>* cols[] = {&p.x, &p.y, &p.z, &p.r, &p.vx, &p.vy, &p.vz, &p.wx, &p.wy, &p.wz};
  for (int c = 0; c < 10; ++c) t.add(names[c], *cols[c]);
  t.add("particle", std::vector<double>(p.particle.begin(), p.particle.end()));
  t.add("previous_particle", std::vector<double>(p.previous_particle.begin(), p.previous_particle.end()));
  {
    H5Writer w(path.string());
    w.write_table("spheres", t);
    w.write_attribute("snapshot", attributes_json);
    w.commit();
  }
  const std::string h5 = path.filename().string();
  const int64_t n = p.size();
  std::ostringstream x;
  auto item = [&](const std::string& col) {
    x << "        <DataItem Dimensions=\"" << n << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5
      << ":/spheres/" << col << "</DataItem>\n";
  };
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n    <Grid Name=\"spheres\" GridType=\"Uniform\">\n"
    << "      <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\"/>\n"
    << "      <Geometry GeometryType=\"X_Y_Z\">\n";
  item("x_m");
  item("y_m");
  item("z_m");
  x << "      </Geometry>\n";
  for (const char* a : {"r_m", "vx_m_s", "vy_m_s", "vz_m_s", "particle"}) {
    x << "      <Attribute Name=\"" << a << "\" AttributeType=\"Scalar\" Center=\"Node\">\n";
    item(a);
    x << "      </Attribute>\n";
  }
  x << "    </Grid>\n  </Domain>\n</Xdmf>\n";
  std::filesystem::path xmf = path;
  xmf.replace_extension(".xmf");
  write_file_atomic(xmf, x.str());
}

}  // namespace tg::dem
