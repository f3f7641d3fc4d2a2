use host_sim::device::LocalDevice;
#[test]
fn probe() {
    let mut d = LocalDevice::new();
    for r in ["MOVE Z=1 X=2","MOVE INC=1 X=1","POS","CFG DIAM=0","MOVE X=-0.00004 Z=-0.00005","POS","MOVE X=+1.500000 Z=-0","POS","MOVE X=1. Z=2","MOVE X=-0.000049","POS","CFG DIAM=1","POS","MOVE X=-0.000099","POS","CFG HX=0.0025 DIAM=0 HZ=0.000001","CFG HX=0.000001 HZ=0.000001","POS","CFG","Cfg hx=0.001 diam=1", "MOVE X=3 INC=0", "CFG HX=0.00005"] {
        println!("{r:?} -> {:?}", d.request(r));
    }
}
