// Uses the installed pcl_movers as a downstream project would.
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/sensor_model.h>

#include <iostream>

int main() {
  const pcl_movers::SensorModel model = pcl_movers::SensorModel::hdl64();
  std::cout << "pcl_movers consumer: " << model.name() << " has " << model.rows() << " beams\n";
  return model.rows() == 64 ? 0 : 1;
}
