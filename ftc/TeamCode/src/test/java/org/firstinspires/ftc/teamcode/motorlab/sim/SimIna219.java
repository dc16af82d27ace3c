/* motorlab JVM test: an INA219 at register level, on the simulated hub's I2C bus. */
package org.firstinspires.ftc.teamcode.motorlab.sim;

import com.qualcomm.robotcore.hardware.I2cAddr;
import com.qualcomm.robotcore.hardware.I2cDeviceSynch;
import com.qualcomm.robotcore.hardware.I2cWaitControl;
import java.util.Random;

/**
 * Registers as the data sheet describes them: configuration (reset value 0x399F), shunt voltage (10 µV,
 * clipped to the PGA range), bus voltage (4 mV in bits 15..3, CNVR bit 1, OVF bit 0), current =
 * shunt·cal/4096 and power = current·bus/5000, calibration (bit 0 reads 0). Readings carry Gaussian
 * noise reduced by √(averaged samples); the bus reading saturates at the 16 V or 32 V range. Each transaction costs {@link #transactionSeconds}.
 */
public final class SimIna219 implements I2cDeviceSynch {
    private final SimHub hub;
    private final Random random;
    public double shuntOhms = 0.1;
    public double busNoiseVolts = 0.02;
    public double shuntNoiseVolts = 20e-6;
    public double transactionSeconds = 1.0e-3;
    public int transactions = 0;
    private int configuration = 0x399F;
    private int calibration = 0;
    private I2cAddr address = I2cAddr.create7bit(0x40);
    private boolean engaged;

    public SimIna219(SimHub hub, long seed) {
        this.hub = hub;
        this.random = new Random(seed);
    }

    private static int samples(int adcCode) {
        return (adcCode & 0x8) != 0 ? 1 << (adcCode & 0x7) : 1;
    }

    private int shuntRegister() {
        double pga = 0.040 * (1 << ((configuration >> 11) & 0x3));
        double noise = shuntNoiseVolts / Math.sqrt(samples((configuration >> 3) & 0xF));
        double v = hub.plant.current() * shuntOhms + noise * random.nextGaussian();
        v = Math.max(-pga, Math.min(pga, v));
        return (int) Math.round(v / 10e-6);
    }

    private int register(int ireg) {
        switch (ireg) {
            case 0x00:
                return configuration;
            case 0x01:
                return shuntRegister() & 0xFFFF;
            case 0x02: {
                double noise = busNoiseVolts / Math.sqrt(samples((configuration >> 7) & 0xF));
                double v = Math.max(0.0, hub.plant.terminalVolts() + noise * random.nextGaussian());
                // Worst case assumed: the reading saturates at the selected full-scale range.
                double fsr = (configuration & 0x2000) != 0 ? 32.0 : 16.0;
                int code = (int) Math.min(Math.round(v / 0.004), Math.round(fsr / 0.004));
                long current = (long) shuntRegister() * calibration / 4096;
                int ovf = Math.abs(current) > 32767 ? 1 : 0;
                return (code << 3) | 0x2 | ovf;
            }
            case 0x03: {
                long current = (long) shuntRegister() * calibration / 4096;
                return (int) Math.min(Math.abs(current) * Math.round(hub.plant.terminalVolts() / 0.004) / 5000, 0xFFFF);
            }
            case 0x04: {
                long current = (long) shuntRegister() * calibration / 4096;
                return (int) Math.max(-32768, Math.min(32767, current)) & 0xFFFF;
            }
            case 0x05:
                return calibration;
            default:
                return 0;
        }
    }

    @Override
    public byte[] read(int ireg, int creg) {
        hub.plant.advance(transactionSeconds);
        transactions++;
        int value = register(ireg);
        byte[] out = new byte[creg];
        for (int k = 0; k < creg; k++) {
            out[k] = (byte) (k % 2 == 0 ? value >> 8 : value); // the pointer does not auto-increment
        }
        return out;
    }

    @Override
    public byte read8(int ireg) {
        return read(ireg, 1)[0];
    }

    @Override
    public void write(int ireg, byte[] data) {
        write(ireg, data, I2cWaitControl.ATOMIC);
    }

    @Override
    public void write(int ireg, byte[] data, I2cWaitControl waitControl) {
        hub.plant.advance(transactionSeconds);
        transactions++;
        if (data.length < 2) {
            return;
        }
        int value = ((data[0] & 0xFF) << 8) | (data[1] & 0xFF);
        if (ireg == 0x00) {
            if ((value & 0x8000) != 0) {
                configuration = 0x399F;
                calibration = 0;
            } else {
                configuration = value;
            }
        } else if (ireg == 0x05) {
            calibration = value & 0xFFFE;
        }
    }

    @Override
    public void write8(int ireg, int bVal) {
        write(ireg, new byte[] {(byte) bVal});
    }

    @Override
    public void write8(int ireg, int bVal, I2cWaitControl waitControl) {
        write(ireg, new byte[] {(byte) bVal}, waitControl);
    }

    @Override
    public void waitForWriteCompletions(I2cWaitControl waitControl) {
    }

    @Override
    public void enableWriteCoalescing(boolean enable) {
    }

    @Override
    public boolean isWriteCoalescingEnabled() {
        return false;
    }

    @Override
    public boolean isArmed() {
        return true;
    }

    @Override
    public void setI2cAddress(I2cAddr newAddress) {
        address = newAddress;
    }

    @Override
    public I2cAddr getI2cAddress() {
        return address;
    }

    @Override
    public void engage() {
        engaged = true;
    }

    @Override
    public void disengage() {
        engaged = false;
    }

    @Override
    public boolean isEngaged() {
        return engaged;
    }

    @Override
    public Manufacturer getManufacturer() {
        return Manufacturer.Adafruit;
    }

    @Override
    public String getDeviceName() {
        return "simulated INA219";
    }

    @Override
    public String getConnectionInfo() {
        return "simulated I2C bus 0, address 0x" + Integer.toHexString(address.get7Bit());
    }

    @Override
    public int getVersion() {
        return 1;
    }

    @Override
    public void resetDeviceConfigurationForOpMode() {
    }

    @Override
    public void close() {
    }
}
